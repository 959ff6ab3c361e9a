"""Shared building blocks of every extractor, in the order data flows through them.

``points``       the valid returns of a scan as a sequence (with the seam of full circles)
``breakpoints``  neighbour-distance tests and clustering (adaptive, ABD, PDBS, fixed)
``denoise``      isolated-noise detection and the paper's window-mean replacement
``corners``      corner scores (slope difference, turn angle) and candidate peaks
``fit``          line fits (total least squares, the paper's 5-point OLS), SSE, covariance
``select``       the threshold sweep and its selection criterion
``merge``        merging collinear neighbours and splitting by a maximum residual
``assemble``     turning sequence positions into an :class:`~scanlines.Extraction`
"""
