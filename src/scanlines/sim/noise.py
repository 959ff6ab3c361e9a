"""Range noise of a simulated laser scanner.

The model turns the exact ranges of one scan into measured ranges, and records for
every beam what happened to it (:class:`BeamStatus`). Its components, applied in this
order, are:

1. **Mixed pixels.** Where two consecutive beams hit different surfaces that do not
   meet (a depth discontinuity of at least ``mixed_pixel_min_jump``), the laser
   footprint of the beam at the edge straddles both surfaces and real scanners
   (SICK LMS in particular) return a range between them. With probability
   ``mixed_pixel_prob`` per discontinuity, one of the two beams (either, with equal
   chance) returns a range drawn uniformly between the two ranges.
2. **Gaussian range noise** with a range-dependent standard deviation
   ``sigma(r) = max(sigma, sigma_rel * r) + sigma_slope * r`` (the presets use the
   ``max`` form of datasheets; the sensor family of :mod:`scanlines.sim.family` the
   additive ``a + b r`` with ``sigma = a``, ``sigma_slope = b``), plus a **per-scan bias**
   ``u * max(bias, bias_rel * r)`` with ``u ~ U(-1, 1)`` drawn once per scan (a
   systematic error shared by all beams of a scan; datasheets state accuracy bounds
   in this ``max(constant, fraction of range)`` shape).
3. **Outliers**: spurious short returns (dust, glass, a passing leg). With
   probability ``outlier_prob`` a beam returns a range drawn uniformly between
   ``range_min`` and ``outlier_max_fraction`` times its true range (or
   ``outlier_far`` when the beam hits nothing).
4. **Quantisation** to multiples of ``quantum`` (1 cm in the CARMEN logs of the
   SICK LMS, 1 mm for Hokuyo and TiM).
5. **Range limits**: a measured range outside ``[range_min, range_max]`` is no return.
6. **Dropouts**: with probability ``dropout_prob`` a beam returns nothing.

All random numbers come from the generator passed in, drawn in a fixed order and in
fixed amounts whatever the probabilities are, so switching one component on or off
does not change the draws of the others.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from scanlines.truth import BeamStatus

__all__ = ["NO_RETURN", "NoiseModel", "NoisyRanges", "apply_noise"]

NO_RETURN = math.inf
"""Range written for a beam with no return (as in ROS ``LaserScan``)."""


@dataclass(frozen=True)
class NoiseModel:
    """Parameters of the simulated range noise (see the module docstring).

    Parameters
    ----------
    sigma:
        Statistical 1-sigma range noise in metres (the floor at short range).
    sigma_rel:
        Statistical 1-sigma as a fraction of the range; the noise is
        ``max(sigma, sigma_rel * r) + sigma_slope * r``.
    sigma_slope:
        Statistical 1-sigma added in proportion to the range (``0`` in the presets):
        with ``sigma = a`` and ``sigma_rel = 0`` the noise is ``a + sigma_slope * r``.
    bias:
        Largest per-scan bias in metres at short range.
    bias_rel:
        Largest per-scan bias as a fraction of the range; the bias of a scan is
        ``u * max(bias, bias_rel * r)`` with ``u ~ U(-1, 1)`` drawn once per scan.
    quantum:
        Range resolution in metres; ``0`` for none.
    dropout_prob:
        Probability that a beam returns nothing.
    outlier_prob:
        Probability that a beam returns a spurious short range.
    outlier_max_fraction:
        Outlier ranges are below this fraction of the true range.
    outlier_far:
        Upper end of outlier ranges for beams that hit nothing, in metres.
    mixed_pixel_prob:
        Probability, per depth discontinuity, of a mixed pixel.
    mixed_pixel_min_jump:
        Smallest range difference in metres between two consecutive beams on
        different surfaces that counts as a depth discontinuity.
    """

    sigma: float = 0.0
    sigma_rel: float = 0.0
    bias: float = 0.0
    bias_rel: float = 0.0
    quantum: float = 0.0
    dropout_prob: float = 0.0
    outlier_prob: float = 0.0
    outlier_max_fraction: float = 0.9
    outlier_far: float = 5.0
    mixed_pixel_prob: float = 0.0
    mixed_pixel_min_jump: float = 0.1
    sigma_slope: float = 0.0

    def __post_init__(self) -> None:
        for name in (
            "sigma",
            "sigma_rel",
            "sigma_slope",
            "bias",
            "bias_rel",
            "quantum",
            "outlier_far",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"NoiseModel.{name} must be finite and >= 0, got {value!r}")
        for name in ("dropout_prob", "outlier_prob", "mixed_pixel_prob", "outlier_max_fraction"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"NoiseModel.{name} must be in [0, 1], got {value!r}")
        if not self.mixed_pixel_min_jump >= 0.0:
            raise ValueError("NoiseModel.mixed_pixel_min_jump must be >= 0")

    @classmethod
    def exact(cls) -> NoiseModel:
        """No noise at all: measured ranges equal the true ranges."""
        return cls()

    def sigma_at(self, ranges: np.ndarray) -> np.ndarray:
        """Statistical 1-sigma at each range."""
        r = np.asarray(ranges, dtype=np.float64)
        finite = np.where(np.isfinite(r), r, 0.0)
        sigma = np.maximum(self.sigma, self.sigma_rel * finite)
        return sigma + self.sigma_slope * finite if self.sigma_slope else sigma

    def effective_sigma(self, ranges: np.ndarray) -> np.ndarray:
        """1-sigma of a measured range about the truth: Gaussian noise and quantisation.

        ``sqrt(sigma_at(r)**2 + quantum**2 / 12)`` (a rounding error is uniform over one
        quantum); the per-scan bias is left out, it moves neighbouring returns together.
        """
        return np.sqrt(self.sigma_at(ranges) ** 2 + self.quantum**2 / 12.0)

    def bias_at(self, ranges: np.ndarray, scale: float) -> np.ndarray:
        """Per-scan bias at each range for the scan's draw ``scale`` in ``[-1, 1]``."""
        r = np.asarray(ranges, dtype=np.float64)
        return scale * np.maximum(self.bias, self.bias_rel * np.where(np.isfinite(r), r, 0.0))

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of the parameters."""
        return asdict(self)


@dataclass(frozen=True, eq=False)
class NoisyRanges:
    """Measured ranges of one scan and what happened to each beam.

    Attributes
    ----------
    ranges:
        Measured ranges; :data:`NO_RETURN` where the beam returned nothing.
    status:
        :class:`BeamStatus` code of each beam (``int8``).
    bias_scale:
        The scan's bias draw ``u`` in ``[-1, 1]``: every range is shifted by
        :meth:`NoiseModel.bias_at` ``(r, u)``.
    """

    ranges: np.ndarray
    status: np.ndarray
    bias_scale: float


def _mixed_pixels(
    true_ranges: np.ndarray,
    jump: np.ndarray,
    noise: NoiseModel,
    draws: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """Ranges with mixed pixels, and the mask of beams that became mixed pixels.

    ``jump[k]`` marks a discontinuity between beam ``k`` and beam ``(k + 1) % n``.
    """
    n = len(true_ranges)
    u_happen, u_side, u_where = draws
    k = np.flatnonzero(jump & (u_happen < noise.mixed_pixel_prob))
    left, right = k, (k + 1) % n
    beam = np.where(u_side[k] < 0.5, left, right)
    lo = np.minimum(true_ranges[left], true_ranges[right])
    hi = np.maximum(true_ranges[left], true_ranges[right])
    ranges = true_ranges.copy()
    ranges[beam] = lo + u_where[k] * (hi - lo)
    mixed = np.zeros(n, dtype=bool)
    mixed[beam] = True
    return ranges, mixed


def _quantise(ranges: np.ndarray, quantum: float) -> np.ndarray:
    if quantum <= 0.0:
        return ranges
    with np.errstate(invalid="ignore"):
        return np.where(np.isfinite(ranges), np.round(ranges / quantum) * quantum, ranges)


def apply_noise(
    true_ranges: np.ndarray,
    jump: np.ndarray,
    noise: NoiseModel,
    rng: np.random.Generator,
    *,
    range_min: float = 0.0,
    range_max: float = math.inf,
) -> NoisyRanges:
    """Turn exact ranges into measured ranges.

    Parameters
    ----------
    true_ranges:
        Exact range of each beam, ``inf`` where the beam hits nothing.
    jump:
        Boolean, one per consecutive beam pair ``(k, k + 1)`` (length ``n - 1``), or
        ``n`` for a full-circle scan whose last entry is the pair ``(n - 1, 0)``: the
        pair straddles two different surfaces that do not meet. Only pairs whose
        ranges also differ by at least ``noise.mixed_pixel_min_jump`` get mixed pixels.
    noise:
        The noise parameters.
    rng:
        Source of randomness (``numpy.random.default_rng(seed)``).
    range_min, range_max:
        The sensor's valid range interval.

    Returns
    -------
    NoisyRanges
    """
    r_true = np.asarray(true_ranges, dtype=np.float64)
    n = len(r_true)
    pair_jump = np.zeros(n, dtype=bool)
    jump = np.asarray(jump, dtype=bool)
    pair_jump[: len(jump)] = jump
    nxt = np.roll(r_true, -1)
    with np.errstate(invalid="ignore"):
        pair_jump &= np.isfinite(r_true) & np.isfinite(nxt)
        pair_jump &= np.abs(nxt - r_true) >= noise.mixed_pixel_min_jump

    mixed_draws = (rng.random(n), rng.random(n), rng.random(n))
    gauss = rng.standard_normal(n)
    bias_scale = float(rng.uniform(-1.0, 1.0))
    u_outlier, u_outlier_range = rng.random(n), rng.random(n)
    u_dropout = rng.random(n)

    ranges, mixed = _mixed_pixels(r_true, pair_jump, noise, mixed_draws)
    hit = np.isfinite(r_true)
    with np.errstate(invalid="ignore"):
        noisy = ranges + noise.sigma_at(ranges) * gauss + noise.bias_at(ranges, bias_scale)
    ranges = np.where(hit, noisy, NO_RETURN)

    outlier = u_outlier < noise.outlier_prob
    reference = np.where(hit, r_true * noise.outlier_max_fraction, noise.outlier_far)
    low = max(range_min, 0.0)
    outlier &= reference > low
    ranges = np.where(outlier, low + u_outlier_range * (reference - low), ranges)

    ranges = _quantise(ranges, noise.quantum)
    with np.errstate(invalid="ignore"):
        in_limits = np.isfinite(ranges) & (ranges > 0.0)
        in_limits &= (ranges >= range_min) & (ranges <= range_max)
    dropout = (u_dropout < noise.dropout_prob) & (hit | outlier)

    status = np.where(hit, BeamStatus.HIT, BeamStatus.NO_HIT).astype(np.int8)
    status[mixed & hit] = BeamStatus.MIXED
    status[outlier] = BeamStatus.OUTLIER
    status[(hit | outlier) & ~in_limits] = BeamStatus.OUT_OF_RANGE
    status[dropout] = BeamStatus.DROPOUT
    returned = np.isin(status, (BeamStatus.HIT, BeamStatus.MIXED, BeamStatus.OUTLIER))
    ranges = np.where(returned, ranges, NO_RETURN)
    return NoisyRanges(ranges=ranges, status=status, bias_scale=bias_scale)
