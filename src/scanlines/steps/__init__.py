"""The building blocks of every extractor, one implementation each, in the order data flows.

Each step is implemented once, in C++ (``cpp/scanlines/steps/``, one file per module here,
compiled at install as :mod:`scanlines._core`). These modules document the steps, declare
their parameters and constants, and give the Python side (the methods whose search is
numpy, ground truth, sensor profiles, the tests) the steps as functions over numpy arrays
and the bundles below; they trust their arguments and validate nothing. A step here is
used by two methods or more; one method's own steps are in its files
(``cpp/scanlines/methods/``, :mod:`scanlines.methods`). The validated
entry points are :class:`~scanlines.Scan` and :class:`~scanlines.Extractor`;
``docs/ARCHITECTURE.md`` gives the conventions.

``returns``      the valid returns of a scan (:class:`~scanlines.steps.returns.Returns`)
``noise``        range noise measured from the scan: one sigma, its growth with range
``breakpoints``  the clustering rules (paper, ABD, PDBS, fixed) and the break test
``clusters``     runs of one surface, with the seam of full circles joined
``denoise``      isolated returns, small and in-between clusters, the paper's window mean
``corners``      corner scores (turn angle, the paper's Dk) and their peaks
``fit``          line fits from running sums (total least squares, the paper's 5-point
                 OLS), fitting costs, covariances (:class:`~scanlines.steps.fit.Moments`)
``select``       the threshold sweep and its criterion (BIC, smallest SSE)
``split``        recursive splits (end-point fit), cuts at corners
``merge``        merging neighbours by chi-square
``events``       corners and breakpoints between consecutive segments
``assemble``     the result arrays of an :class:`~scanlines.Extraction`
``arrays``       the array types the compiled steps take
"""

__all__ = [
    "arrays",
    "assemble",
    "breakpoints",
    "clusters",
    "corners",
    "denoise",
    "events",
    "fit",
    "merge",
    "noise",
    "returns",
    "select",
    "split",
]
