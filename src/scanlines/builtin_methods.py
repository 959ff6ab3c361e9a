"""The names of the built-in methods, in listing order, known without loading any kernel.

The command line offers them as the choices of ``--method`` before the methods are
imported, so that a command starts (and ``scanlines view`` serves its page) at once.
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
