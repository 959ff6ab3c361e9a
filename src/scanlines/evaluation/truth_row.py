"""The truth row: the true segments fitted to their own returns, an oracle to compare with.

The spec ``truth`` (:data:`~scanlines.evaluation.specs.TRUTH`) is not a method but a
reference row, built from each scene's truth by :func:`truth_extraction`: the true
segments' beam runs, each fitted by total least squares to the scan's measured returns
the truth says hit that segment's edge, with the true breakpoints and corners. It is
scored like every method, with the same tolerances: the best any segmentation can do
with exact boundaries, the ceiling of the segment metrics (its breakpoint and corner F1
are 1 by construction). It needs the truth, so it is not an extraction method and not
in :func:`scanlines.method_names`.

This is the one module of :mod:`scanlines.evaluation` that reaches into the extraction
steps (:mod:`scanlines.steps`) rather than the public API: it assembles an
:class:`~scanlines.Extraction` from given segments the way the methods do.
"""

from __future__ import annotations

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.specs import TRUTH
from scanlines.scan import is_full_circle
from scanlines.steps.assemble import assemble, to_extraction
from scanlines.steps.fit import TLS, run_labels
from scanlines.steps.returns import Returns
from scanlines.truth import Truth

__all__ = ["truth_extraction"]


def truth_extraction(scan: Scan, truth: Truth, *, range_sigma: float = 0.0) -> Extraction:
    """The truth row of a scan: its true segments fitted to its own measured returns.

    Every true segment becomes one segment over the same beams (``first`` and
    ``last`` from the truth), fitted by total least squares, as the methods fit
    (:func:`scanlines.steps.assemble.assemble`), to the scan's returns in that run
    that the truth says hit the segment's edge (:attr:`Truth.true_return`: no
    outliers, mixed pixels or dropouts). Breakpoints and corners are the true ones;
    outliers are the returns of no surface (outliers and mixed pixels).

    Parameters
    ----------
    scan, truth:
        A simulated scan and its truth.
    range_sigma:
        Range noise in metres for the segments' covariances (they are not scored).

    Returns
    -------
    Extraction
        With ``method == "truth"``: the best any segmentation can do with exact
        boundaries.
    """
    seg, n = truth.segments, truth.n_beams
    spans = (seg.last - seg.first) % n + 1
    beams, owner = run_labels(seg.first, seg.first + spans - 1)
    beams %= n  # a segment across the seam of a full circle
    keep = scan.valid[beams] & truth.true_return[beams] & (truth.edge[beams] == seg.edge[owner])
    beams, owner = beams[keep], owner[keep]
    b = np.cumsum(np.bincount(owner, minlength=len(seg))) - 1
    a = np.concatenate(([0], b[:-1] + 1)).astype(np.intp)
    r, bearing = scan.ranges[beams], scan.angle_increment * beams  # beam 0 at bearing 0
    returns = Returns(beams, r, r * np.cos(bearing), r * np.sin(bearing))
    events = (
        truth.breakpoints.astype(np.int64),
        truth.corners.astype(np.int64),
        np.union1d(truth.outliers, truth.mixed_pixels).astype(np.int64),
    )
    sigma = np.full(r.size, float(range_sigma))
    shape = (n, is_full_circle(n, scan.angle_increment))
    arrays = assemble(returns, TLS, a.astype(np.int64), b, scan.angle_min, sigma, events, shape)
    return to_extraction(arrays, TRUTH, {"range_sigma": range_sigma})
