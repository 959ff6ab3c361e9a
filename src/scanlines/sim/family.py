"""The simulator as a family of sensors, not four presets.

:func:`random_sensor` draws one 2D laser scanner from the family; :func:`corner_sensors`
are its four extremes; :func:`family_sensors` the drawn members and the corners, each
with a stable name that :func:`scanlines.sim.get_sensor` resolves (``"family-07"``,
``"corner-fine-noisy"``), so every tool that takes a sensor by name takes them.

The family (every number drawn independently; "log-uniform" means uniform in the
logarithm):

=====================  ==========================================================
range noise            Gaussian, ``sigma(r) = a + b r`` (``NoiseModel(sigma=a,
                       sigma_slope=b)``), ``a`` log-uniform in 0.3-3 cm, ``b``
                       uniform in 0-3 % of the range
per-scan bias          ``u * max(c, d r)``, ``u ~ U(-1, 1)`` per scan, with
                       ``c = U(0, 2) a`` and ``d = U(0, 2) b`` (datasheets state a
                       systematic error of 2-3 times the statistical one)
angular resolution     log-uniform in 0.1-1 deg
field of view          a full circle (360 deg) with probability 1/4, else uniform
                       in 180-340 deg, centred on the front; at most 3600 beams
range limits           ``range_min`` uniform in 2-10 cm; ``range_max``
                       log-uniform in 5.6-80 m, capped so that the
                       range-proportional noise stays plausible:
                       ``b * range_max <= 25 cm`` (a scanner with 3 % noise is a
                       short-range triangulation scanner, not an 80 m one), never
                       below 5.6 m
dropouts               probability per beam uniform in 0-3 %
outliers               probability per beam uniform in 0-2 %; ranges up to 90 %
                       of the true range, or up to ``min(5 m, range_max)`` for
                       beams that hit nothing
mixed pixels           probability per depth discontinuity uniform in 20-80 %
quantisation           1 mm
=====================  ==========================================================

The four **corner sensors** are the extreme combinations of noise and resolution, all
360 deg (full circle) so that they differ in nothing else: ``corner-fine-quiet``
(0.1 deg, 3600 beams; ``a`` = 0.3 cm, ``b`` = 0, no bias, no dropouts or outliers,
mixed pixels 20 %, 80 m), ``corner-fine-noisy`` (0.1 deg; ``a`` = 3 cm, ``b`` = 3 %,
the largest bias ``c = 2a``, ``d = 2b``, 3 % dropouts, 2 % outliers, mixed pixels
80 %, range 8.33 m by the cap above), ``corner-coarse-quiet`` and
``corner-coarse-noisy`` (the same at 1 deg, 360 beams).

Member ``k`` of the family with seed ``s`` is drawn from
``numpy.random.default_rng(SeedSequence([s, k, 2026]))``: it does not depend on how
many members are drawn. Its name is ``family-kk`` for seed 0, ``family-sS-kk`` else.
"""

from __future__ import annotations

import math
import re
from functools import lru_cache

import numpy as np

from scanlines.errors import ParameterError
from scanlines.sim.noise import NoiseModel
from scanlines.sim.sensors import SENSORS, SensorSpec

__all__ = [
    "BIAS_FACTOR",
    "CORNER_NAMES",
    "DROPOUT",
    "FOV_DEG",
    "FULL_CIRCLE_PROB",
    "MAX_BEAMS",
    "MIXED_PIXEL",
    "NOISE_A",
    "NOISE_B",
    "OUTLIER",
    "RANGE_MAX",
    "RANGE_MIN",
    "RESOLUTION_DEG",
    "SLOPE_REACH",
    "corner_sensors",
    "family_name",
    "family_names",
    "family_sensor",
    "family_sensors",
    "get_sensor",
    "random_sensor",
]

NOISE_A = (0.003, 0.03)
"""Range of the constant noise term ``a`` in metres (log-uniform)."""
NOISE_B = (0.0, 0.03)
"""Range of the range-proportional noise term ``b`` (uniform)."""
BIAS_FACTOR = (0.0, 2.0)
"""The bias bounds ``c``, ``d`` are these multiples of ``a``, ``b`` (uniform)."""
RESOLUTION_DEG = (0.1, 1.0)
"""Angular resolution in degrees (log-uniform)."""
FOV_DEG = (180.0, 340.0)
"""Field of view in degrees of the partial scanners (uniform)."""
FULL_CIRCLE_PROB = 0.25
"""Probability that a scanner sees the full circle."""
MAX_BEAMS = 3600
"""Largest number of beams (360 deg at 0.1 deg)."""
RANGE_MIN = (0.02, 0.10)
"""Smallest range in metres (uniform)."""
RANGE_MAX = (5.6, 80.0)
"""Largest range in metres (log-uniform), before the cap :data:`SLOPE_REACH`."""
SLOPE_REACH = 0.25
"""Cap on the range: ``b * range_max <= SLOPE_REACH`` metres (never below 5.6 m)."""
DROPOUT = (0.0, 0.03)
"""Dropout probability per beam (uniform)."""
OUTLIER = (0.0, 0.02)
"""Outlier probability per beam (uniform)."""
MIXED_PIXEL = (0.2, 0.8)
"""Mixed-pixel probability per depth discontinuity (uniform)."""
QUANTUM = 0.001
"""Range resolution in metres."""

CORNER_NAMES = (
    "corner-fine-quiet",
    "corner-fine-noisy",
    "corner-coarse-quiet",
    "corner-coarse-noisy",
)
"""The corner sensors: finest/coarsest resolution x lowest/highest noise."""

_ENTROPY_TAG = 2026
_NAME = re.compile(r"family-(?:s(\d+)-)?(\d+)")


def _log_uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    lo, hi = bounds
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _range_max(drawn: float, b: float) -> float:
    cap = SLOPE_REACH / b if b > 0 else math.inf
    return max(RANGE_MAX[0], min(drawn, cap))


def _sensor(
    name: str,
    *,
    a: float,
    b: float,
    bias_c: float,
    bias_d: float,
    resolution_deg: float,
    fov_deg: float | None,
    range_min: float,
    range_max: float,
    dropout: float,
    outlier: float,
    mixed: float,
) -> SensorSpec:
    """A family member; ``fov_deg=None`` for a full circle."""
    step = math.radians(resolution_deg)
    if fov_deg is None:
        n_beams = min(MAX_BEAMS, round(2.0 * math.pi / step))
        step = 2.0 * math.pi / n_beams
        angle_min = -math.pi
        view = "360 deg"
    else:
        n_beams = min(MAX_BEAMS, math.floor(math.radians(fov_deg) / step) + 1)
        angle_min = -step * (n_beams - 1) / 2.0
        view = f"{math.degrees(step * (n_beams - 1)):.1f} deg"
    noise = NoiseModel(
        sigma=a,
        sigma_slope=b,
        bias=bias_c,
        bias_rel=bias_d,
        quantum=QUANTUM,
        dropout_prob=dropout,
        outlier_prob=outlier,
        outlier_far=min(5.0, range_max),
        mixed_pixel_prob=mixed,
    )
    return SensorSpec(
        name=name,
        n_beams=n_beams,
        angle_min=angle_min,
        angle_increment=step,
        range_min=range_min,
        range_max=range_max,
        noise=noise,
        description=(
            f"family: {view} at {math.degrees(step):.3f} deg ({n_beams} beams), "
            f"sigma = {100 * a:.2f} cm + {100 * b:.2f} % r, range {range_min:.2f}-"
            f"{range_max:.1f} m"
        ),
    )


def random_sensor(rng: np.random.Generator, name: str = "family") -> SensorSpec:
    """Draw one sensor of the family (the ranges: the module docstring).

    The draws are made in a fixed order and number, so the same generator state
    gives the same sensor.
    """
    a = _log_uniform(rng, NOISE_A)
    b = float(rng.uniform(*NOISE_B))
    bias_c, bias_d = (float(f) for f in rng.uniform(*BIAS_FACTOR, size=2))
    resolution = _log_uniform(rng, RESOLUTION_DEG)
    full = bool(rng.random() < FULL_CIRCLE_PROB)
    fov = float(rng.uniform(*FOV_DEG))
    range_min = float(rng.uniform(*RANGE_MIN))
    range_max = _range_max(_log_uniform(rng, RANGE_MAX), b)
    dropout, outlier, mixed = (float(rng.uniform(*r)) for r in (DROPOUT, OUTLIER, MIXED_PIXEL))
    return _sensor(
        name,
        a=a,
        b=b,
        bias_c=bias_c * a,
        bias_d=bias_d * b,
        resolution_deg=resolution,
        fov_deg=None if full else fov,
        range_min=range_min,
        range_max=range_max,
        dropout=dropout,
        outlier=outlier,
        mixed=mixed,
    )


def _corner(name: str) -> SensorSpec:
    _, resolution, level = name.split("-")
    noisy = level == "noisy"
    a, b = (NOISE_A[1], NOISE_B[1]) if noisy else (NOISE_A[0], NOISE_B[0])
    return _sensor(
        name,
        a=a,
        b=b,
        bias_c=BIAS_FACTOR[1] * a if noisy else 0.0,
        bias_d=BIAS_FACTOR[1] * b if noisy else 0.0,
        resolution_deg=RESOLUTION_DEG[0] if resolution == "fine" else RESOLUTION_DEG[1],
        fov_deg=None,
        range_min=RANGE_MIN[0],
        range_max=_range_max(RANGE_MAX[1], b),
        dropout=DROPOUT[1] if noisy else DROPOUT[0],
        outlier=OUTLIER[1] if noisy else OUTLIER[0],
        mixed=MIXED_PIXEL[1] if noisy else MIXED_PIXEL[0],
    )


def corner_sensors() -> tuple[SensorSpec, ...]:
    """The four extremes of the family, in the order of :data:`CORNER_NAMES`."""
    return tuple(_corner(name) for name in CORNER_NAMES)


def family_name(index: int, seed: int = 0) -> str:
    """Name of member ``index`` of the family drawn with ``seed``."""
    return f"family-{index:02d}" if seed == 0 else f"family-s{seed}-{index:02d}"


def _member(index: int, seed: int) -> SensorSpec:
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, _ENTROPY_TAG]))
    return random_sensor(rng, family_name(index, seed))


def family_names(count: int = 24, seed: int = 0) -> tuple[str, ...]:
    """Names of :func:`family_sensors` ``(count, seed)``: the members, then the corners."""
    if isinstance(count, bool) or not isinstance(count, int) or count < 0:
        raise ValueError(f"count must be an integer >= 0, got {count!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    return (*(family_name(k, seed) for k in range(count)), *CORNER_NAMES)


def family_sensors(count: int = 24, seed: int = 0) -> tuple[SensorSpec, ...]:
    """``count`` sensors drawn from the family with ``seed``, then the four corners."""
    return tuple(family_sensor(name) for name in family_names(count, seed))


@lru_cache(maxsize=256)
def family_sensor(name: str) -> SensorSpec | None:
    """The family sensor called ``name`` (a member or a corner); ``None`` if there is none."""
    if name in CORNER_NAMES:
        return _corner(name)
    match = _NAME.fullmatch(name)
    if match is None or (match.group(1) is not None and int(match.group(1)) == 0):
        return None
    seed = int(match.group(1) or 0)
    index = int(match.group(2))
    if family_name(index, seed) != name:  # one spelling per member
        return None
    return _member(index, seed)


def get_sensor(sensor: str | SensorSpec) -> SensorSpec:
    """The preset called ``sensor`` (a :class:`SensorSpec` is returned unchanged).

    Names of the sensor family (``"family-07"``, ``"family-s3-07"``,
    ``"corner-fine-noisy"``) resolve to their sensors too.

    Raises
    ------
    ParameterError
        For an unknown name; the message lists the presets and the family's names.
    """
    if isinstance(sensor, SensorSpec):
        return sensor
    try:
        return SENSORS[sensor]
    except KeyError:
        member = family_sensor(sensor) if isinstance(sensor, str) else None
        if member is not None:
            return member
        known = ", ".join(sorted(SENSORS))
        raise ParameterError(
            f"unknown sensor preset {sensor!r}; known: {known}; family: family-00, family-01, "
            "..., family-s<seed>-<index>, corner-{fine,coarse}-{quiet,noisy}"
        ) from None
