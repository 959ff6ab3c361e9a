"""The repeatability scores of one method on a log's scan pairs, loose and strict."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.repeat_pairs import (
    PairRecord,
    RepeatTolerances,
    _moved,
    _share_in_view,
    match_segments,
)
from scanlines.evaluation.specs import MethodSpec
from scanlines.extraction import END_X, END_Y, START_X, START_Y
from scanlines.geometry.registration import invert, transform_points
from scanlines.sensor.profile import SensorProfile

# --------------------------------------------------------------------------- scores


@dataclass
class _Counts:
    scans: int = 0
    valid: int = 0
    covered: int = 0
    segments: int = 0
    unfitted: int = 0
    few: int = 0
    surface: float = 0.0
    long: int = 0
    repeated: int = 0
    trials: int = 0
    matched: int = 0
    lengths: list = field(default_factory=list)


@dataclass(frozen=True)
class MethodRepeatability:
    """The scores of one method spec on one log (see :mod:`scanlines.evaluation.repeatability`)."""

    spec: MethodSpec
    scans: int
    segments: int
    unfitted: int
    long_segments: int
    repeated: int
    trials: int
    matched: int
    repeatability: float
    per_pair: float
    coverage: float
    median_length: float
    short_share: float
    per_scan: float
    per_metre: float
    strict: float = math.nan
    repeated_metres: float = math.nan
    strict_pairs: int = 0
    fidelity_mm: float = math.nan
    fidelity_segments: int = 0

    def to_dict(self) -> dict[str, Any]:
        """Flat row for CSV (spec columns first)."""
        row = {"label": self.spec.label, "spec": self.spec.text}
        return row | {k: v for k, v in asdict(self).items() if k != "spec"}


def _on_segments(extraction: Extraction, valid: np.ndarray) -> np.ndarray:
    n = len(valid)
    marks = np.zeros(n + 1, dtype=np.intp)
    for first, last in zip(extraction.first.tolist(), extraction.last.tolist(), strict=True):
        if first <= last:
            marks[first] += 1
            marks[last + 1] -= 1
        else:  # across the seam of a full circle
            marks[first] += 1
            marks[n] -= 1
            marks[0] += 1
            marks[last + 1] -= 1
    on = np.cumsum(marks[:n]) > 0
    on[extraction.outliers] = False
    return on & valid


def _surface_length(scan: Scan, extraction: Extraction, on: np.ndarray) -> float:
    index = np.flatnonzero(scan.valid)
    if len(index) < 2:
        return 0.0
    pts = scan.points[index]
    step = np.hypot(*np.diff(pts, axis=0).T)
    gap = np.isin(index[:-1], extraction.breakpoints)
    keep = on[index[:-1]] & on[index[1:]] & ~gap
    return float(step[keep].sum())


def _ends(extraction: Extraction) -> np.ndarray:
    return np.asarray(extraction.lines[:, [START_X, START_Y, END_X, END_Y]], dtype=np.float64)


def _score_method(
    spec: MethodSpec,
    scans: Sequence[tuple[int, Scan]],
    pairs: Sequence[PairRecord],
    tol: RepeatTolerances,
    on_scan: Callable[[], None] | None,
    profile: SensorProfile | None,
) -> MethodRepeatability:
    extractor = spec.extractor(sensor_profile=profile)
    counts = _Counts()
    ends: dict[int, np.ndarray] = {}
    for index, scan in scans:
        extraction = extractor(scan)
        on = _on_segments(extraction, scan.valid)
        counts.scans += 1
        counts.valid += int(np.count_nonzero(scan.valid))
        counts.covered += int(np.count_nonzero(on))
        counts.segments += len(extraction)
        counts.few += int(np.count_nonzero(extraction.n_points < tol.few_points))
        counts.surface += _surface_length(scan, extraction, on)
        segment_ends = _ends(extraction)
        lengths = np.hypot(*(segment_ends[:, 2:4] - segment_ends[:, 0:2]).T)
        counts.unfitted += int(np.count_nonzero(~np.isfinite(lengths)))
        counts.lengths.extend(lengths[np.isfinite(lengths)].tolist())
        ends[index] = segment_ends
        if on_scan is not None:
            on_scan()
    strict, metres, strict_pairs, fidelity = _strict_scores(ends, dict(scans), pairs, tol)
    partners: dict[int, list[PairRecord]] = {}
    for pair in pairs:
        if pair.used:
            partners.setdefault(pair.i, []).append(pair)
    for i, used in partners.items():
        mine = ends[i]
        long = np.hypot(*(mine[:, 2:4] - mine[:, 0:2]).T) >= tol.min_length
        if not long.any():
            continue
        repeated = np.zeros(int(long.sum()), dtype=bool)
        for pair in used:
            hit = match_segments(mine[long], _moved(ends[pair.j], pair.pose), tol).any(axis=1)
            counts.trials += len(hit)
            counts.matched += int(hit.sum())
            repeated |= hit
        counts.long += len(repeated)
        counts.repeated += int(repeated.sum())
    return MethodRepeatability(
        spec=spec,
        scans=counts.scans,
        segments=counts.segments,
        unfitted=counts.unfitted,
        long_segments=counts.long,
        repeated=counts.repeated,
        trials=counts.trials,
        matched=counts.matched,
        repeatability=_ratio(counts.repeated, counts.long),
        per_pair=_ratio(counts.matched, counts.trials),
        coverage=_ratio(counts.covered, counts.valid),
        median_length=float(np.median(counts.lengths)) if counts.lengths else math.nan,
        short_share=_ratio(counts.few, counts.segments),
        per_scan=_ratio(counts.segments, counts.scans),
        per_metre=_ratio(counts.segments, counts.surface),
        strict=strict,
        repeated_metres=metres,
        strict_pairs=strict_pairs,
        fidelity_mm=1000.0 * float(np.median(fidelity)) if fidelity else math.nan,
        fidelity_segments=len(fidelity),
    )


SURFACE_SAMPLES = 11
"""Points along a segment that decide whether the other scan of a pair observed it."""


def _strict_scores(
    ends: Mapping[int, np.ndarray],
    scans: Mapping[int, Scan],
    pairs: Sequence[PairRecord],
    tol: RepeatTolerances,
) -> tuple[float, float, int, list[float]]:
    """The strict measure: each used pair scored on its own, in both directions.

    In direction ``i -> j`` the trials are ``i``'s long segments whose surface ``j``
    observed (at least half of :data:`SURFACE_SAMPLES` points along the segment in
    ``j``'s view, not hidden behind ``j``'s returns), weighted by length; one is repeated
    when a segment of ``j``, moved into ``i``'s frame, matches it with the lines compared
    in Hesse form in ``i``'s frame (``|d rho| <= strict_distance``). A pair scores the
    mean of its two directions' repeated length over trial length; the log, the mean over
    pairs (``strict``) and the mean repeated metres per scan and direction
    (``repeated_metres``); also the number of pairs scored, and the fidelity of every
    long segment of either direction (:func:`segment_fidelity`, metres; segments with
    too few of the other scan's returns near them left out).
    """
    hesse = replace(tol, distance_at="origin", distance=tol.strict_distance)
    scores, metres, fidelity = [], [], []
    for pair in pairs:
        if not pair.used:
            continue
        ratios, repeated_lengths = [], []
        for mine, theirs, pose, other in (
            (ends[pair.i], ends[pair.j], pair.pose, scans[pair.j]),
            (ends[pair.j], ends[pair.i], invert(pair.pose), scans[pair.i]),
        ):
            trial, repeated, fits = _direction(mine, theirs, pose, other, tol, hesse)
            repeated_lengths.append(repeated)
            fidelity.extend(fits)
            if trial > 0:
                ratios.append(repeated / trial)
        metres.append(float(np.mean(repeated_lengths)))
        if ratios:
            scores.append(float(np.mean(ratios)))
    return (
        float(np.mean(scores)) if scores else math.nan,
        float(np.mean(metres)) if metres else math.nan,
        len(scores),
        fidelity,
    )


def _direction(mine, theirs, pose, other, tol, hesse) -> tuple[float, float, list[float]]:
    """Trial and repeated length of one direction of a pair (see :func:`_strict_scores`),
    and the fidelity of ``mine``'s long segments; ``pose`` moves ``other`` into ``mine``'s
    frame."""
    lengths = np.hypot(*(mine[:, 2:4] - mine[:, 0:2]).T) if len(mine) else np.zeros(0)
    long = np.flatnonzero(np.isfinite(lengths) & (lengths >= tol.min_length))
    if len(long) == 0:
        return 0.0, 0.0, []
    returns = transform_points(other.points[other.valid], pose)
    fits = segment_fidelity(mine[long], returns, tol.fidelity_band, tol.fidelity_returns)
    to_other = invert(pose)
    share = np.linspace(0.0, 1.0, SURFACE_SAMPLES)[:, None]
    observed = np.zeros(len(long), dtype=bool)
    for k, m in enumerate(long):
        samples = mine[m, 0:2] + share * (mine[m, 2:4] - mine[m, 0:2])
        moved = transform_points(samples, to_other)
        observed[k] = _share_in_view(moved, other, tol.occlusion_margin) >= 0.5
    long = long[observed]
    fidelity = fits[np.isfinite(fits)].tolist()
    if len(long) == 0:
        return 0.0, 0.0, fidelity
    hit = match_segments(mine[long], _moved(theirs, pose), hesse).any(axis=1)
    return float(lengths[long].sum()), float(lengths[long][hit].sum()), fidelity


def segment_fidelity(
    ends: np.ndarray, returns: np.ndarray, band: float = 0.10, least: int = 5
) -> np.ndarray:
    """How well each segment describes another scan's view of its surface: the RMS
    distance to the segment's line of the ``returns`` that fall within its extent (their
    projection onto the line between its ends) and within ``band`` of its line; NaN for a
    segment with fewer than ``least`` such returns.

    ``ends`` are ``N x 4`` (start x, y, end x, y) and ``returns`` ``K x 2``, in one frame.
    """
    ends = np.asarray(ends, dtype=np.float64).reshape(-1, 4)
    returns = np.asarray(returns, dtype=np.float64).reshape(-1, 2)
    out = np.full(len(ends), math.nan)
    for k, (ax, ay, bx, by) in enumerate(ends):
        length = math.hypot(bx - ax, by - ay)
        if not length > 0.0:
            continue
        ux, uy = (bx - ax) / length, (by - ay) / length
        dx, dy = returns[:, 0] - ax, returns[:, 1] - ay
        along, across = dx * ux + dy * uy, uy * dx - ux * dy
        near = (along >= 0.0) & (along <= length) & (np.abs(across) <= band)
        if np.count_nonzero(near) >= least:
            out[k] = math.sqrt(float(np.mean(across[near] ** 2)))
    return out


def _ratio(a: float, b: float) -> float:
    return a / b if b else math.nan
