"""What a laser scanner is like, measured from its own data: :class:`SensorProfile`.

A profile holds the range noise as a function of range (binned, with an uncertainty,
and the :class:`~scanlines.steps.noise.NoiseLine` every threshold takes its sigma
from), the beam geometry, the range quantum, the codes and rates of beams without a
return, and the rates of outliers and mixed pixels::

    from scanlines import Extractor, open_log
    from scanlines.sensor.profile import estimate_profile, read_profile

    profile = estimate_profile(open_log("run.log"), source="run.log")
    profile.save("lms.json")
    extractor = Extractor(sensor_profile=read_profile("lms.json"))

Features are a pure function of (scan, parameters, profile): ``scanlines run`` resolves
one profile for the whole log (given, or estimated from its first scans) and records
it in the output's metadata; an :class:`~scanlines.Extractor` without one measures the
noise of each scan from that scan alone.

How the noise is measured: each return with three neighbours on each side on one surface
gives the difference between its range and a parabola fitted to the seven ranges over
the beam index (:func:`scanlines.steps.noise.local_residuals`). The samples are cut into
range bins of equal count; a bin's sigma is the median absolute sample over 0.6745, its
uncertainty the standard deviation of that value over a bootstrap of whole scans. The
noise line is a weighted least-squares fit through the bins (slope not below zero).
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.scan import Scan
from scanlines.sensor.mounting import estimate_mounting
from scanlines.sensor.profile_file import (
    PROFILE_FORMAT,
    ProfileError,
    checked_fields,
    read_values,
)
from scanlines.steps.noise import (
    MIN_NOISE_SIGMA,
    NoiseLine,
    local_residuals,
    noise_at,
    scan_noise,
)
from scanlines.steps.returns import beam_gaps, valid_returns

__all__ = [
    "PROFILE_FORMAT",
    "NoiseBin",
    "ProfileError",
    "SensorProfile",
    "estimate_mounting",
    "estimate_profile",
    "read_profile",
    "scan_noise_line",
]

DEFAULT_SCANS = 500
"""Scans a profile is measured from by default (the first of the log)."""

MAX_BINS = 8
MIN_BIN_SAMPLES = 200
BOOTSTRAP_ROUNDS = 50
SPIKE_SIGMAS = 6.0
JUMP = 0.3
"""Range step (m) that counts as a depth jump for the mixed-pixel rate."""


@dataclass(frozen=True)
class NoiseBin:
    """Range noise in one range bin: ``sigma`` (m) at the bin's median ``range`` (m),
    its bootstrap ``error`` (m) and the number of ``samples``."""

    range: float
    sigma: float
    error: float
    samples: int


@dataclass(frozen=True)
class SensorProfile:
    """A sensor as its data show it (module docstring).

    Attributes
    ----------
    noise_sigma0, noise_per_metre:
        The noise line ``sigma(r) = sigma0 + per_metre r`` (m, m/m), floored at 1 mm.
    noise_bins:
        The measured curve behind it.
    beams, angle_min, angle_increment:
        Beam geometry of the scans measured (radians).
    range_min, range_max:
        The scans' valid range interval; ``largest_range`` the largest return seen.
    range_quantum:
        Step the ranges are stored in (m), 0 when none is found.
    repeated_ranges:
        Share of neighbouring returns with exactly the same range (sensors or drivers
        that repeat one reading over several beams).
    no_return_codes:
        Values that beams without a return carry in the log, with their share of those
        beams (``"nan"``, ``"inf"`` or a number).
    dropout_rate:
        Share of beams without a return.
    outlier_rate:
        Share of returns (with a neighbour on each side) that lie more than 6 sigma off
        their neighbours while those agree with each other (spikes).
    mixed_pixel_rate:
        Share of depth jumps of more than 0.3 m with one return between the two
        surfaces, more than 6 sigma from both.
    mounting:
        The laser's ``(x, y, theta)`` on the robot where the log records both poses.
    source, scans:
        Where the profile was measured and from how many scans.
    """

    noise_sigma0: float
    noise_per_metre: float
    noise_bins: tuple[NoiseBin, ...] = ()
    beams: int = 0
    angle_min: float = math.nan
    angle_increment: float = math.nan
    range_min: float = 0.0
    range_max: float = math.inf
    largest_range: float = math.nan
    range_quantum: float = 0.0
    repeated_ranges: float = math.nan
    no_return_codes: dict[str, float] = field(default_factory=dict)
    dropout_rate: float = math.nan
    outlier_rate: float = math.nan
    mixed_pixel_rate: float = math.nan
    mounting: tuple[float, float, float] | None = None
    source: str = ""
    scans: int = 0

    @property
    def noise(self) -> NoiseLine:
        """The noise line the extractors take."""
        return NoiseLine(self.noise_sigma0, self.noise_per_metre)

    def sigma_at(self, r: float | np.ndarray) -> np.ndarray:
        """Range noise sigma (m) at range(s) ``r``."""
        return np.maximum(
            self.noise_sigma0 + self.noise_per_metre * np.asarray(r, float), MIN_NOISE_SIGMA
        )

    @property
    def field_of_view(self) -> float:
        """Angle covered by the beams (radians)."""
        return abs(self.angle_increment) * self.beams

    def to_dict(self) -> dict[str, Any]:
        """The profile as JSON-ready values (the file format of :meth:`save`)."""
        out = asdict(self)
        out["noise_bins"] = [asdict(b) for b in self.noise_bins]
        out["mounting"] = None if self.mounting is None else list(self.mounting)
        for key, value in out.items():
            if isinstance(value, float) and not math.isfinite(value):
                out[key] = str(value)
        return {"format": PROFILE_FORMAT, **out}

    def save(self, path: str | Path) -> Path:
        """Write the profile as JSON to ``path``."""
        from scanlines.outputs import write_text_atomically

        return write_text_atomically(path, json.dumps(self.to_dict(), indent=2) + "\n")

    @classmethod
    def from_dict(cls, values: dict[str, Any], where: str = "profile") -> SensorProfile:
        """A profile from :meth:`to_dict`'s values; :class:`ProfileError` names what is
        wrong (:func:`~scanlines.sensor.profile_file.checked_fields`)."""
        kwargs = checked_fields(values, where, tuple(cls.__dataclass_fields__))
        kwargs["noise_bins"] = tuple(NoiseBin(*b) for b in kwargs.get("noise_bins", ()))
        return cls(**kwargs)


def read_profile(path: str | Path) -> SensorProfile:
    """The profile saved at ``path`` (:meth:`SensorProfile.save`): a regular JSON file of
    at most :data:`~scanlines.sensor.profile_file.MAX_PROFILE_BYTES`, nested at most a few
    levels deep (:func:`~scanlines.sensor.profile_file.read_values`)."""
    return SensorProfile.from_dict(read_values(path), where=str(path))


def as_profile(profile: SensorProfile | str | Path | None) -> SensorProfile | None:
    """A profile given as itself, a file path, or ``None``."""
    if profile is None or isinstance(profile, SensorProfile):
        return profile
    if isinstance(profile, (str, Path)):
        return read_profile(profile)
    raise ProfileError(f"sensor_profile must be a SensorProfile or a path, got {profile!r}")


# --------------------------------------------------------------------------- measuring


@dataclass
class _Tally:
    """What :func:`estimate_profile` collects scan by scan."""

    samples: list[np.ndarray] = field(default_factory=list)
    at: list[np.ndarray] = field(default_factory=list)
    beams: int = 0
    returns: int = 0
    repeated: int = 0
    neighbours: int = 0
    codes: dict[str, int] = field(default_factory=dict)
    ranges_seen: list[np.ndarray] = field(default_factory=list)
    largest: float = 0.0
    first: Scan | None = None
    scans: int = 0
    early_returns: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)


def estimate_profile(
    scans: Iterable[Scan], *, max_scans: int = DEFAULT_SCANS, source: str = ""
) -> SensorProfile:
    """Measure a :class:`SensorProfile` from up to ``max_scans`` scans of one sensor.

    Raises :class:`ProfileError` when the scans hold too few returns on surfaces to
    measure the noise.
    """
    tally = _Tally()
    for scan in scans:
        if tally.scans >= max_scans:
            break
        _tally_scan(tally, scan)
    if tally.first is None:
        raise ProfileError(f"{source or 'log'}: no scans to measure a sensor profile from")
    bins = _noise_bins(tally.samples, tally.at)
    if not bins:
        raise ProfileError(
            f"{source or 'log'}: too few returns on surfaces to measure the range noise "
            f"({sum(map(len, tally.samples))} samples in {tally.scans} scans)"
        )
    sigma0, per_metre = _noise_line(bins)
    noise = NoiseLine(sigma0, per_metre)
    outliers, mixed = _spike_rates(tally, noise)
    first = tally.first
    invalid = tally.beams - tally.returns
    return SensorProfile(
        noise_sigma0=sigma0,
        noise_per_metre=per_metre,
        noise_bins=tuple(bins),
        beams=len(first),
        angle_min=first.angle_min,
        angle_increment=first.angle_increment,
        range_min=first.range_min,
        range_max=first.range_max,
        largest_range=tally.largest,
        range_quantum=_quantum(np.concatenate(tally.ranges_seen)),
        repeated_ranges=tally.repeated / max(tally.neighbours, 1),
        no_return_codes={k: v / max(invalid, 1) for k, v in _top(tally.codes).items()},
        dropout_rate=invalid / max(tally.beams, 1),
        outlier_rate=outliers,
        mixed_pixel_rate=mixed,
        source=source,
        scans=tally.scans,
    )


def scan_noise_line(scan: Scan) -> NoiseLine:
    """The range noise measured from ``scan`` alone (what an extractor without a sensor
    profile takes for that scan)."""
    return NoiseLine(*(float(v) for v in scan_noise(*_returns_of(scan))))


def noise_samples(scan: Scan) -> tuple[np.ndarray, np.ndarray]:
    """One scan's range-noise samples and the ranges they were taken at (what
    :func:`estimate_profile` pools over scans)."""
    return local_residuals(*_returns_of(scan))


def noise_samples_of(ranges, valid, cos, sin) -> tuple[np.ndarray, np.ndarray]:
    """:func:`noise_samples` of a scan's arrays: its ranges, its mask of beams with a return
    and its bearing tables relative to beam 0."""
    returns = valid_returns(ranges, valid, cos, sin)
    return local_residuals(returns, beam_gaps(returns.index, ranges.shape[0]))


def pooled_noise_line(samples: list[np.ndarray], at: list[np.ndarray]) -> NoiseLine | None:
    """The noise line of pooled per-scan samples, as :func:`estimate_profile` measures it;
    None when they are too few."""
    bins = _noise_bins(samples, at)
    return NoiseLine(*_noise_line(bins)) if bins else None


def _returns_of(scan: Scan):
    n = len(scan)
    local = scan.angle_increment * np.arange(n)
    # writable copies: a scan's read-only arrays would compile the kernel a second time
    ranges, valid = np.array(scan.ranges), np.array(scan.valid)
    returns = valid_returns(ranges, valid, np.cos(local), np.sin(local))
    return returns, beam_gaps(returns.index, n)


def _tally_scan(tally: _Tally, scan: Scan) -> None:
    if tally.first is None:
        tally.first = scan
    tally.scans += 1
    returns, gap = _returns_of(scan)
    sample, at = local_residuals(returns, gap)
    tally.samples.append(sample)
    tally.at.append(at)
    tally.beams += len(scan)
    tally.returns += returns.r.size
    adjacent = gap == 1
    tally.neighbours += int(adjacent.sum())
    tally.repeated += int((np.diff(returns.r)[adjacent] == 0.0).sum())
    if returns.r.size:
        tally.largest = max(tally.largest, float(returns.r.max()))
    if len(tally.ranges_seen) < 50:
        tally.ranges_seen.append(returns.r[:200])
    for value in scan.ranges[~scan.valid][:1000]:
        key = "nan" if math.isnan(value) else ("inf" if math.isinf(value) else f"{value:g}")
        tally.codes[key] = tally.codes.get(key, 0) + 1
    if tally.scans <= 200:
        tally.early_returns.append((returns.r, gap))


def _noise_bins(samples: list[np.ndarray], at: list[np.ndarray]) -> list[NoiseBin]:
    """Equal-count range bins of the pooled samples, each with a scan bootstrap error."""
    sample, where = np.concatenate(samples), np.concatenate(at)
    count = min(MAX_BINS, sample.size // MIN_BIN_SAMPLES)
    if count == 0:
        return []
    edges = np.quantile(where, np.linspace(0.0, 1.0, count + 1))
    edges[-1] = np.inf
    scan_of = np.repeat(np.arange(len(samples)), [s.size for s in samples])
    rng = np.random.default_rng(0)
    rounds = [rng.integers(0, len(samples), len(samples)) for _ in range(BOOTSTRAP_ROUNDS)]
    times_drawn = [np.bincount(chosen, minlength=len(samples)) for chosen in rounds]
    bins = []
    for low, high in itertools.pairwise(edges):
        inside = (where >= low) & (where < high)
        if not inside.any():
            continue
        part = sample[inside]
        sigma = float(np.median(part) / 0.6745)
        order = np.argsort(part, kind="stable")  # once for every round's weighted median
        ordered, owners = part[order], scan_of[inside][order]
        redraws = []
        for times in times_drawn:
            weights = times[owners]
            if weights.any():
                redraws.append(_weighted_median(ordered, weights) / 0.6745)
        error = float(np.std(redraws)) if redraws else math.nan
        bins.append(NoiseBin(float(np.median(where[inside])), sigma, error, int(part.size)))
    return bins


def _weighted_median(ordered: np.ndarray, weights: np.ndarray) -> float:
    """The weighted median of ``ordered`` (sorted ascending), weights non-negative."""
    cumulative = np.cumsum(weights)
    return float(ordered[np.searchsorted(cumulative, 0.5 * cumulative[-1])])


def _noise_line(bins: list[NoiseBin]) -> tuple[float, float]:
    """Weighted least-squares line through the bins (weights 1 / error^2), slope >= 0."""
    r = np.array([b.range for b in bins])
    s = np.array([b.sigma for b in bins])
    error = np.array([b.error for b in bins])
    floor = max(float(np.nanmedian(error)) if np.isfinite(error).any() else 0.0, 1e-5)
    w = 1.0 / np.maximum(np.nan_to_num(error, nan=floor), floor) ** 2
    mean_r, mean_s = np.average(r, weights=w), np.average(s, weights=w)
    spread = np.sum(w * (r - mean_r) ** 2)
    slope = max(float(np.sum(w * (r - mean_r) * (s - mean_s)) / spread), 0.0) if spread else 0.0
    return max(float(mean_s - slope * mean_r), 0.0), slope


def _spike_rates(tally: _Tally, noise: NoiseLine) -> tuple[float, float]:
    """Outlier (spike) and mixed-pixel rates over the first scans (see :class:`SensorProfile`).

    A depth jump is a step of more than :data:`JUMP` between returns whose outer
    neighbours continue their own surfaces (steps under a third of that); it is a mixed
    pixel when one return lies between the two surfaces, more than 6 sigma from both.
    """
    spikes = triples = mixed = clean = 0
    for r, gap in tally.early_returns:
        if r.size < 5:
            continue
        joined = (gap[:-1] == 1) & (gap[1:] == 1)
        before, middle, after = r[:-2][joined], r[1:-1][joined], r[2:][joined]
        sigma = np.maximum(noise.sigma0 + noise.per_metre * middle, MIN_NOISE_SIGMA)
        agree = np.abs(after - before) < 3.0 * math.sqrt(2.0) * sigma
        off = np.abs(middle - 0.5 * (before + after)) > SPIKE_SIGMAS * sigma
        triples += int(agree.sum())
        spikes += int((agree & off).sum())
        mixed += _mixed_pixels(r, gap, noise)
        clean += _clean_jumps(r, gap)
    outlier_rate = spikes / triples if triples else math.nan
    mixed_rate = mixed / (mixed + clean) if mixed + clean else math.nan
    return outlier_rate, mixed_rate


def _mixed_pixels(r: np.ndarray, gap: np.ndarray, noise: NoiseLine) -> int:
    """Five consecutive returns ``p0 p1 m p3 p4``: a jump from ``p1`` to ``p3`` with ``m``
    between both surfaces, the outer pairs continuing their surfaces."""
    ok = (gap[:-3] == 1) & (gap[1:-2] == 1) & (gap[2:-1] == 1) & (gap[3:] == 1)
    p0, p1, m, p3, p4 = (r[k : r.size - 4 + k][ok] for k in range(5))
    sigma = np.maximum(noise.sigma0 + noise.per_metre * m, MIN_NOISE_SIGMA)
    low, high = np.minimum(p1, p3), np.maximum(p1, p3)
    flat = (np.abs(p1 - p0) < JUMP / 3) & (np.abs(p4 - p3) < JUMP / 3)
    between = (m > low + SPIKE_SIGMAS * sigma) & (m < high - SPIKE_SIGMAS * sigma)
    return int((flat & (high - low > JUMP) & between).sum())


def _clean_jumps(r: np.ndarray, gap: np.ndarray) -> int:
    """Four consecutive returns ``p0 p1 p2 p3`` with a jump from ``p1`` to ``p2`` and the
    outer pairs continuing their surfaces."""
    ok = (gap[:-2] == 1) & (gap[1:-1] == 1) & (gap[2:] == 1)
    p0, p1, p2, p3 = (r[k : r.size - 3 + k][ok] for k in range(4))
    flat = (np.abs(p1 - p0) < JUMP / 3) & (np.abs(p3 - p2) < JUMP / 3)
    return int((flat & (np.abs(p2 - p1) > JUMP)).sum())


def _quantum(ranges: np.ndarray) -> float:
    """The coarsest of 1 cm, 1 mm, 0.1 mm that nearly all ranges are multiples of (else 0)."""
    ranges = ranges[np.isfinite(ranges)]
    if ranges.size == 0:
        return 0.0
    for quantum in (0.01, 0.001, 0.0001):
        steps = ranges / quantum
        if np.mean(np.abs(steps - np.round(steps)) < 1e-3) > 0.99:
            return quantum
    return 0.0


def _top(codes: dict[str, int], most: int = 3) -> dict[str, int]:
    return dict(sorted(codes.items(), key=lambda kv: (-kv[1], kv[0]))[:most])


def describe(profile: SensorProfile) -> list[tuple[str, str]]:
    """Rows of (what, value) that summarise a profile for people."""
    deg, p = math.degrees, profile
    near, far = (1000 * noise_at(p.noise, r) for r in (1.0, 5.0))
    codes = ", ".join(f"{code} ({100 * share:.0f} %)" for code, share in p.no_return_codes.items())
    rows = [
        ("noise", f"{1000 * p.noise_sigma0:.2f} mm + {100 * p.noise_per_metre:.2f} % of range"),
        ("noise at 1 m / 5 m", f"{near:.1f} / {far:.1f} mm"),
        ("beams", f"{p.beams} x {deg(abs(p.angle_increment)):.4g} deg"),
        ("field of view", f"{deg(p.field_of_view):.4g} deg"),
        ("valid ranges", f"{p.range_min:g} to {p.range_max:g} m"),
        ("largest range seen", f"{p.largest_range:.3g} m"),
        ("range quantum", f"{p.range_quantum:g} m"),
        ("no return", f"{100 * p.dropout_rate:.1f} % of beams; codes {codes or 'none'}"),
        ("outliers", f"{100 * p.outlier_rate:.2f} % of returns"),
        ("mixed pixels", f"{100 * p.mixed_pixel_rate:.1f} % of depth jumps"),
        ("repeated ranges", f"{100 * p.repeated_ranges:.1f} % of neighbours"),
    ]
    if p.mounting is not None:
        x, y, theta = p.mounting
        rows.append(("mounting", f"x {x:.3f} m, y {y:.3f} m, theta {deg(theta):.2f} deg"))
    rows.append(("measured from", f"{p.scans} scans of {p.source or 'the log'}"))
    return rows
