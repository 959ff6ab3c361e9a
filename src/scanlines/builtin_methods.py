"""The names of the built-in methods, in listing order, known without importing them.

The command line offers them as the choices of ``--method``, and the configuration, the
runs and the benchmarks name the default, without importing :mod:`scanlines.methods`:
that imports numpy and every method's module (a few hundred milliseconds; loading the
compiled core is a millisecond of it), which a command's ``--help`` and parsing need not
wait for.

Each name is a module of :mod:`scanlines.methods` whose class registers under that
name; :data:`scanlines.methods.REGISTRY` lists the same names in the same order (tested).
"""

BUILTIN_METHODS = (
    "adaptive",
    "paper",
    "iepf",
    "pdbs",
    "split_merge",
    "line_tracking",
    "line_regression",
    "ransac",
    "hough",
    "partition",
    "surfaces",
)

#: The method used where none is named: ``Extractor()``, ``scanlines run``, a configuration.
DEFAULT_METHOD = "adaptive"
