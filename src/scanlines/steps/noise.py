"""Range noise: a line ``sigma(r) = sigma0 + per_metre r`` measured from the data.

``NoiseLine``          the noise model every threshold takes its sigma from.
``noise_at``           ``sigma`` at a range.
``local_residuals``    noise samples of a scan: each return's range against a smooth
                       fit to its neighbours' ranges.
``scan_noise``         the :class:`NoiseLine` of one scan, from its samples.
``covariance_sigmas``  each return's sigma for the segment covariances.

A method given a sensor profile's line uses it; without one, each scan measures its own
(:func:`scan_noise`). What the adaptive method alone takes from the noise (a scale from
the lines of a first segmentation, the residual bound's tolerances) is in its own files
(:mod:`scanlines.methods.adaptive`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from scanlines import _core
from scanlines.steps.arrays import int64s
from scanlines.steps.returns import Returns

__all__ = [
    "MIN_NOISE_SIGMA",
    "UNKNOWN_NOISE",
    "NoiseLine",
    "covariance_sigmas",
    "local_residuals",
    "noise_at",
    "scan_noise",
]

MIN_NOISE_SIGMA: float = _core.MIN_NOISE_SIGMA
"""Floor (metres) of the estimated noise: ranges logged to 1 mm or 1 cm carry at
least this much quantisation noise, and a noise-free simulation must not make
the criterion divide by zero."""


class NoiseLine(NamedTuple):
    """Range noise ``sigma(r) = max(sigma0 + per_metre r, MIN_NOISE_SIGMA)``, metres.

    NaN fields mean "not known": measure it from the scan (:func:`resolve_noise`).
    """

    sigma0: float
    per_metre: float


UNKNOWN_NOISE = NoiseLine(math.nan, math.nan)
"""The noise of a method built without a sensor profile: each scan measures its own."""


def noise_at(noise: NoiseLine, r):
    """The noise sigma of ``noise`` at range ``r`` (a number or an array)."""
    return np.maximum(noise.sigma0 + noise.per_metre * r, MIN_NOISE_SIGMA)


def local_residuals(returns: Returns, gap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Range-noise samples of a scan and the range of each: ``(sample, at)``.

    Each return with three neighbours on each side (no gap of two or more missing beams
    among them) gives the difference between its range and a parabola in the beam index
    fitted to the window's ranges (``parabola_at_centre``), over the square root of
    ``1 - h`` (``h`` the return's leverage in that fit). Seven points span more than one
    reading of sensors that repeat a range over two or three beams (the URG-04LX logs of
    the Mines robot), where the second difference of ranges reads zero. Along a straight
    surface the range is smooth in the bearing, so the difference is range noise alone;
    only surfaces within 45 deg of facing the beam give samples. Windows across corners
    and jumps are few, and the robust statistics of :func:`scan_noise` ignore them.
    Unlike an orthogonal distance from a fitted line, this does not depend on the line's
    direction, which noise larger than the spacing of the returns makes arbitrary.
    """
    return _core.local_residuals(*returns, int64s(gap))


def scan_noise(returns: Returns, gap: np.ndarray) -> NoiseLine:
    """The :class:`NoiseLine` of one scan, from its :func:`local_residuals`.

    The samples are cut into up to 4 bins of equal count by range (at least 40 each, or
    one bin of fewer); each bin gives a robust sigma (median absolute sample / 0.6745) at
    its median range, and a least-squares line through those points, weighted by the
    inverse variance of each bin's sigma, gives the model. A slope less than 2 standard
    errors above zero gives a constant instead (clamping a noisy slope at zero would bias
    the noise far away upwards). Fewer than 5 samples: the constant
    :data:`MIN_NOISE_SIGMA`.
    """
    return NoiseLine(*_core.scan_noise(*returns, int64s(gap)))


def covariance_sigmas(
    range_sigma: float, noise: NoiseLine, returns: Returns, gap: np.ndarray
) -> np.ndarray:
    """Per-return sigma of the segment covariances: the ``range_sigma`` override where it
    is a number (NaN: not given), else ``noise`` if known, else the scan's own."""
    return _core.covariance_sigmas(float(range_sigma), tuple(noise), *returns, int64s(gap))
