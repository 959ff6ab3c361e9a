"""Denoising before breakpoint detection (Steps 2-3, eq. 5 and 20 of [1]_).

Two readings of the paper's isolated-noise rule:

``literal_noise``  Step 2 as written: point ``i`` is noise when ``d_{i-1} > d_{i-2}``
                   and ``d_i > d_{i+1}``. On real scans this fires on a large share
                   of ordinary points (any local bump of the neighbour distance).
``isolated_noise`` the tighter reading used by default: point ``i`` is noise when
                   the breakpoint test separates it from *both* neighbours while
                   those two neighbours pass the test with each other (a spike
                   that would otherwise form a one-point cluster).

Step 3 replaces a noise point and its two neighbours by the mean of a window of
``N`` points centred on it (``window_means``). The window never
spans a pair of returns that the raw breakpoint test separates, so smoothing
cannot move a breakpoint. The default instead drops an isolated point (it then
counts as one missing beam, which clustering bridges): no point is invented. It
also drops single-return clusters and two-return clusters that lie in depth between
their neighbours (mixed pixels); ``denoise`` is the whole stage.

The kernels are C++ (``cpp/scanlines/steps/denoise.cpp``), called by the adaptive
method's kernel; their bindings in :mod:`scanlines._core` serve the tests.

References
----------
.. [1] Electronics 11(11), 1759, 2022 (doi:10.3390/electronics11111759), sec. 2.1 and sec. 3.
"""

from __future__ import annotations

import numpy as np

from scanlines.steps.arrays import float64s, int64s
from scanlines.steps.returns import Returns

__all__ = [
    "DENOISE",
    "DENOISE_CODES",
    "ISOLATED",
    "LITERAL",
    "NO_DENOISE",
]

DENOISE = ("isolated", "paper", "none")
DENOISE_CODES = {name: code for code, name in enumerate(DENOISE)}
ISOLATED, LITERAL, NO_DENOISE = range(3)


def _returns(returns: Returns) -> tuple[np.ndarray, ...]:
    index, r, x, y = returns
    return int64s(index), float64s(r), float64s(x), float64s(y)
