"""Range noise measured from the scan itself.

``range_noise``        one sigma for the scan, from second differences of ranges.
``noise_growth``       how the noise grows with range, from each return's distance to
                       the chord of its neighbours.
``residual_noise``     one sigma from the fitted lines of a first segmentation.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines._jit import kernel
from scanlines.steps.fit import run_cost

__all__ = [
    "MIN_NOISE_SIGMA",
    "MIN_RUN_FOR_NOISE",
    "chord_samples",
    "noise_growth",
    "range_noise",
    "residual_noise",
]

MIN_NOISE_SIGMA = 1e-3
"""Floor (metres) of the estimated noise: ranges logged to 1 mm or 1 cm carry at
least this much quantisation noise, and a noise-free simulation must not make
the criterion divide by zero."""

MIN_CHORD_COS = 0.5
"""Chord samples of :func:`noise_growth` come from surfaces within 60 deg of facing the beam."""

MIN_RUN_FOR_NOISE = 8
"""Fewest points of a run that :func:`residual_noise` measures (short runs fit their
own noise)."""


@kernel
def range_noise(r, gap):
    """Robust range-noise sigma of a scan, in metres.

    On a smooth surface the second difference of three consecutive ranges,
    ``r_{i+1} - 2 r_i + r_{i-1}``, is noise with standard deviation ``sigma sqrt(6)``
    (its geometric part, ``r'' dtheta^2``, is far smaller at the resolutions of real
    scanners); the median absolute value, robust to the few corners and edges, gives
    ``sigma``. Triples across a missing beam are left out; ``gap`` as
    :func:`~scanlines.steps.returns.beam_gaps`.
    """
    n = r.shape[0]
    second = np.empty(n)
    count = 0
    for i in range(1, n - 1):
        if gap[i - 1] == 1 and gap[i] == 1:
            second[count] = abs(r[i + 1] - 2.0 * r[i] + r[i - 1])
            count += 1
    if count < 3:
        return MIN_NOISE_SIGMA
    sigma = np.median(second[:count]) / (0.6745 * math.sqrt(6.0))
    return max(sigma, MIN_NOISE_SIGMA)


@kernel
def chord_samples(returns, gap):
    """Range-noise samples from chords, and the range of each: ``(sample, at)``.

    Each return ``P_i`` with neighbours on both sides gives one sample: its distance
    from the chord ``P_{i-1} P_{i+1}`` over ``sqrt(1.5) cos(beta)`` (``beta`` the angle
    between its beam and the chord's normal; only ``beta`` < 60 deg). On a straight
    surface that distance is noise alone, at any incidence and resolution, where the
    second difference of the ranges also holds the surface's geometry (at 1 deg, on
    slanted walls far away, as much as the noise).
    """
    _, r, x, y = returns
    n = r.shape[0]
    sample = np.empty(n)
    at = np.empty(n)
    count = 0
    for i in range(1, n - 1):
        if not (gap[i - 1] == 1 and gap[i] == 1):
            continue
        cx, cy = x[i + 1] - x[i - 1], y[i + 1] - y[i - 1]
        length = math.hypot(cx, cy)
        if length == 0.0 or r[i] <= 0.0:
            continue
        nx, ny = -cy / length, cx / length
        cos_beta = abs(nx * x[i] + ny * y[i]) / r[i]
        if cos_beta < MIN_CHORD_COS:
            continue
        off = abs((x[i] - x[i - 1]) * nx + (y[i] - y[i - 1]) * ny)
        sample[count] = off / (cos_beta * math.sqrt(1.5))
        at[count] = r[i]
        count += 1
    return sample[:count], at[:count]


@kernel
def noise_growth(returns, gap):
    """How the range noise grows with range: ``(sigma_far, slope, far_range)``.

    The samples of :func:`chord_samples` are split at their median range; the robust
    noise of each half and the median range of each half give a line
    ``sigma(r) = sigma_far + slope (r - far_range)`` (``slope >= 0``, 0 when the noise does
    not grow, as on sensors with a constant range error).
    """
    sample, at = chord_samples(returns, gap)
    if sample.shape[0] < 6:
        return 0.0, 0.0, 0.0
    middle = np.median(at)
    near, far = at <= middle, at > middle
    if not far.any():
        return 0.0, 0.0, 0.0
    sigma_near, sigma_far = np.median(sample[near]) / 0.6745, np.median(sample[far]) / 0.6745
    near_range, far_range = np.median(at[near]), np.median(at[far])
    if far_range <= near_range:
        return 0.0, 0.0, 0.0
    return sigma_far, max((sigma_far - sigma_near) / (far_range - near_range), 0.0), far_range


@kernel
def residual_noise(cost, a, b, fallback):
    """Range noise from the fits of the runs ``[a, b]``: the median of ``sqrt(cost / (n - 2))``.

    Only runs of :data:`MIN_RUN_FOR_NOISE` points or more count; the median ignores
    the few runs that still hide a corner. ``cost`` is a
    :class:`~scanlines.steps.fit.RunCost`; ``fallback`` is returned without any such run.
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
    return max(np.median(per_run[:count]), MIN_NOISE_SIGMA)
