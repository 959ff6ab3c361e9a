"""Range noise: a line ``sigma(r) = sigma0 + per_metre r`` measured from the data.

``NoiseLine``          the noise model every threshold takes its sigma from.
``noise_at``           ``sigma`` at a range.
``local_residuals``    noise samples of a scan: each return's range against a smooth
                       fit to its neighbours' ranges.
``scan_noise``         the :class:`NoiseLine` of one scan, from its samples.
``resolve_noise``      a sensor profile's line when given, else the scan's own.
``residual_noise``     a scale of the noise from the fitted lines of a first
                       segmentation.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from scanlines._jit import kernel
from scanlines.steps.fit import run_cost
from scanlines.steps.returns import MAX_BRIDGED_GAP

__all__ = [
    "MIN_NOISE_SIGMA",
    "MIN_RUN_FOR_NOISE",
    "NOISE_HALF_WINDOW",
    "UNKNOWN_NOISE",
    "NoiseLine",
    "covariance_sigmas",
    "local_residuals",
    "noise_at",
    "noise_line_of",
    "residual_noise",
    "residual_tolerances",
    "resolve_noise",
    "return_sigmas",
    "scan_noise",
    "variance_sums",
]

MIN_NOISE_SIGMA = 1e-3
"""Floor (metres) of the estimated noise: ranges logged to 1 mm or 1 cm carry at
least this much quantisation noise, and a noise-free simulation must not make
the criterion divide by zero."""

NOISE_HALF_WINDOW = 3
"""Neighbours on each side of a return in the fit its residual is measured from.
Seven points span more than one reading of sensors that repeat a range over two or
three beams (the URG-04LX logs of the Mines robot), where the second difference of
ranges, or the distance from the chord of the two neighbours, reads zero."""

MIN_SAMPLES_PER_BIN = 40
"""Fewest samples in a range bin of :func:`noise_line_of`."""

MAX_BINS = 4

SLOPE_SIGNIFICANCE = 2.0
"""Standard errors a noise slope must stand above zero to count (:func:`noise_line_of`)."""

MIN_SAMPLES = 5
"""Fewest samples :func:`noise_line_of` measures a noise from."""

RESIDUAL_SIGMAS = 5.0
"""Noise sigmas a return may lie from its segment's line before the residual bound cuts
the segment (:func:`residual_tolerances`): Gaussian noise puts one return in about 1.7
million farther, so on a noisy sensor the bound cuts at shapes, not at noise."""

MIN_RUN_FOR_NOISE = 8
"""Fewest points of a run that :func:`residual_noise` measures (short runs fit their
own noise)."""


class NoiseLine(NamedTuple):
    """Range noise ``sigma(r) = max(sigma0 + per_metre r, MIN_NOISE_SIGMA)``, metres.

    NaN fields mean "not known": measure it from the scan (:func:`resolve_noise`).
    """

    sigma0: float
    per_metre: float


UNKNOWN_NOISE = NoiseLine(math.nan, math.nan)
"""The noise of a method built without a sensor profile: each scan measures its own."""


@kernel
def noise_at(noise, r):
    """The noise sigma of :class:`NoiseLine` ``noise`` at range ``r``."""
    return max(noise.sigma0 + noise.per_metre * r, MIN_NOISE_SIGMA)


@kernel
def local_residuals(returns, gap):
    """Range-noise samples of a scan and the range of each: ``(sample, at)``.

    Each return with :data:`NOISE_HALF_WINDOW` neighbours on each side (no gap of two
    or more missing beams among them) gives the difference between its range and a
    parabola in the beam index fitted to the window's ranges, over the square root of
    ``1 - h`` (``h`` the return's leverage in that fit). Along a straight surface the
    range is smooth in the bearing, so the difference is range noise alone; only
    surfaces within 45 deg of facing the beam give samples (the parabola follows the
    range of steeper ones less well). Windows across corners and jumps are few, and
    the robust statistics of :func:`noise_line_of` ignore them. Unlike an orthogonal
    distance from a fitted line, this does not depend on the line's direction, which
    noise larger than the spacing of the returns makes arbitrary.
    """
    index, r, x, y = returns
    n = r.shape[0]
    h = NOISE_HALF_WINDOW
    sample = np.empty(n)
    at = np.empty(n)
    count = 0
    if n < 2 * h + 1:
        return sample[:0], at[:0]
    stretch_start = np.empty(n, dtype=np.int64)
    stretch_start[0] = 0
    for i in range(1, n):
        stretch_start[i] = stretch_start[i - 1] if gap[i - 1] <= MAX_BRIDGED_GAP else i
    # A window without missing beams has the offsets -h..h: the same sums every time
    # (small integers, exact in any order of summation).
    contiguous = offset_power_sums(np.arange(2 * h + 1), np.int64(0), np.int64(2 * h), np.int64(h))
    for i in range(h, n - h):
        if stretch_start[i + h] > i - h or r[i] <= 0.0:
            continue
        a, b = i - h, i + h
        sums = contiguous if index[b] - index[a] == 2 * h else offset_power_sums(index, a, b, i)
        residual, leverage, slope = parabola_at_centre(index, r, a, b, i, sums)
        if not leverage < 1.0:
            continue
        bearing = abs(math.atan2(x[a] * y[b] - y[a] * x[b], x[a] * x[b] + y[a] * y[b]))
        per_beam = bearing / (index[b] - index[a])
        if not abs(slope) <= r[i] * per_beam:  # tan(incidence) <= 1
            continue
        sample[count] = abs(residual) / math.sqrt(1.0 - leverage)
        at[count] = r[i]
        count += 1
    return sample[:count], at[:count]


@kernel
def offset_power_sums(index, a, b, i):
    """Sums of ``t^0 .. t^4`` over the beam offsets ``t = index[p] - index[i]`` of
    positions ``a..b`` (scalars: no allocation per return)."""
    s0 = s1 = s2 = s3 = s4 = 0.0
    for p in range(a, b + 1):
        t = float(index[p] - index[i])
        t_2 = t * t
        s0 += 1.0
        s1 += t
        s2 += t_2
        s3 += t_2 * t
        s4 += t_2 * t_2
    return s0, s1, s2, s3, s4


@kernel
def parabola_at_centre(index, r, a, b, i, sums):
    """Least-squares parabola of ``r`` over the beam offsets ``index - index[i]`` of
    positions ``a..b`` (``sums``: their :func:`offset_power_sums`):
    ``(r[i] - fit at i, leverage of i, slope at i per beam)``."""
    s0, s1, s2, s3, s4 = sums
    t0 = t1 = t2 = 0.0
    for p in range(a, b + 1):
        t = float(index[p] - index[i])
        t0 += r[p]
        t1 += r[p] * t
        t2 += r[p] * t * t
    # Normal equations M (c0, c1, c2) = (t0, t1, t2), M symmetric with entries s[j + k].
    m00, m01, m02, m11, m12, m22 = s0, s1, s2, s2, s3, s4
    c00 = m11 * m22 - m12 * m12
    c01 = m02 * m12 - m01 * m22
    c02 = m01 * m12 - m02 * m11
    det = m00 * c00 + m01 * c01 + m02 * c02
    if det == 0.0:
        return 0.0, 1.0, 0.0
    c11 = m00 * m22 - m02 * m02
    c12 = m01 * m02 - m00 * m12
    value = (c00 * t0 + c01 * t1 + c02 * t2) / det
    slope = (c01 * t0 + c11 * t1 + c12 * t2) / det
    return r[i] - value, c00 / det, slope


@kernel
def noise_line_of(sample, at):
    """The :class:`NoiseLine` of noise samples ``sample`` taken at ranges ``at``.

    The samples are cut into up to :data:`MAX_BINS` bins of equal count by range (at
    least :data:`MIN_SAMPLES_PER_BIN` each, or one bin of fewer); each bin gives a
    robust sigma (median absolute sample / 0.6745) at its median range, and a
    least-squares line through those points, weighted by the inverse variance of each
    bin's sigma, gives the model. A slope less than :data:`SLOPE_SIGNIFICANCE` standard
    errors above zero gives a constant instead (clamping a noisy slope at zero would
    bias the noise far away upwards). Fewer than :data:`MIN_SAMPLES` samples: NaN.
    """
    n = sample.shape[0]
    bins = min(MAX_BINS, n // MIN_SAMPLES_PER_BIN)
    if bins == 0:
        if n < MIN_SAMPLES:
            return NoiseLine(math.nan, math.nan)
        bins = 1
    order = np.argsort(at, kind="mergesort")
    sigma = np.empty(bins)
    where = np.empty(bins)
    weight = np.empty(bins)
    for k in range(bins):
        part = order[k * n // bins : (k + 1) * n // bins]
        sigma[k] = np.median(sample[part]) / 0.6745
        where[k] = np.median(at[part])
        # the median's standard error is about 1.17 sigma / sqrt(count) (Gaussian samples)
        weight[k] = part.shape[0] / max(1.17 * sigma[k], MIN_NOISE_SIGMA) ** 2
    total = np.sum(weight)
    mean_r, mean_s = np.sum(weight * where) / total, np.sum(weight * sigma) / total
    spread = np.sum(weight * (where - mean_r) ** 2)
    slope = 0.0
    if bins > 1 and spread > 0.0:
        slope = np.sum(weight * (where - mean_r) * (sigma - mean_s)) / spread
        if slope < SLOPE_SIGNIFICANCE / math.sqrt(spread):
            slope = 0.0  # not told apart from constant noise: a constant, unbiased
    return NoiseLine(max(mean_s - slope * mean_r, 0.0), slope)


@kernel
def scan_noise(returns, gap):
    """The :class:`NoiseLine` of one scan (:func:`local_residuals`, :func:`noise_line_of`);
    a constant :data:`MIN_NOISE_SIGMA` when the scan has too few samples."""
    sample, at = local_residuals(returns, gap)
    noise = noise_line_of(sample, at)
    if noise.sigma0 != noise.sigma0:
        return NoiseLine(MIN_NOISE_SIGMA, 0.0)
    return noise


@kernel
def resolve_noise(noise, returns, gap):
    """``noise`` (a sensor profile's :class:`NoiseLine`) if known, else the scan's own."""
    if noise.sigma0 == noise.sigma0:
        return noise
    return scan_noise(returns, gap)


@kernel
def residual_noise(cost, a, b, fallback):
    """Noise from the fits of the runs ``[a, b]``: the median of ``sqrt(cost / (n - 2))``.

    Only runs of :data:`MIN_RUN_FOR_NOISE` points or more count; the median ignores
    the few runs that still hide a corner. ``cost`` is a
    :class:`~scanlines.steps.fit.RunCost` (in noise units, the result is a scale of
    the noise model); ``fallback`` is returned without any such run.
    """
    per_run = np.empty(a.shape[0])
    count = 0
    for k in range(a.shape[0]):
        if b[k] - a[k] + 1 >= MIN_RUN_FOR_NOISE:
            value = math.sqrt(run_cost(cost, a[k], b[k]) / (b[k] - a[k] - 1))
            if math.isfinite(value):
                per_run[count] = value
                count += 1
    if count == 0:
        return fallback
    return np.median(per_run[:count])


@kernel
def return_sigmas(r, noise):
    """The noise sigma of :class:`NoiseLine` ``noise`` at each range of ``r``."""
    out = np.empty(r.shape[0])
    for i in range(r.shape[0]):
        out[i] = noise_at(noise, r[i])
    return out


@kernel
def residual_tolerances(r, noise, floor):
    """How far each return (at ranges ``r``) may lie from its segment's line: ``floor``
    (metres), or :data:`RESIDUAL_SIGMAS` times the noise sigma at its range where that
    is more."""
    out = np.empty(r.shape[0])
    for i in range(r.shape[0]):
        out[i] = max(floor, RESIDUAL_SIGMAS * noise_at(noise, r[i]))
    return out


@kernel
def variance_sums(sigma):
    """Running sums of ``sigma^2``: the ``variances`` of a
    :class:`~scanlines.steps.fit.RunCost`."""
    out = np.zeros(sigma.shape[0] + 1)
    for i in range(sigma.shape[0]):
        out[i + 1] = out[i] + sigma[i] * sigma[i]
    return out


@kernel
def covariance_sigmas(range_sigma, noise, returns, gap):
    """Per-return sigma of the segment covariances: the ``range_sigma`` override where it
    is a number (NaN: not given), else ``noise`` as :func:`resolve_noise` resolves it."""
    if range_sigma == range_sigma:
        return np.full(returns.r.shape[0], range_sigma)
    return return_sigmas(returns.r, resolve_noise(noise, returns, gap))
