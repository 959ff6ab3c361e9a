"""The repeatability scores of one method on a log's scan pairs, loose and strict."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.registration import invert, transform_points
from scanlines.evaluation.repeat_pairs import (
    PairRecord,
    RepeatTolerances,
    _moved,
    _share_in_view,
    match_segments,
)
from scanlines.evaluation.specs import MethodSpec
from scanlines.extraction import END_X, END_Y, START_X, START_Y
from scanlines.sensor_profile import SensorProfile

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
    strict, metres, strict_pairs = _strict_scores(ends, dict(scans), pairs, tol)
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
    )


SURFACE_SAMPLES = 11
"""Points along a segment that decide whether the other scan of a pair observed it."""


def _strict_scores(
    ends: Mapping[int, np.ndarray],
    scans: Mapping[int, Scan],
    pairs: Sequence[PairRecord],
    tol: RepeatTolerances,
) -> tuple[float, float, int]:
    """The strict measure: each used pair scored on its own, in both directions.

    In direction ``i -> j`` the trials are ``i``'s long segments whose surface ``j``
    observed (at least half of :data:`SURFACE_SAMPLES` points along the segment in
    ``j``'s view, not hidden behind ``j``'s returns), weighted by length; one is repeated
    when a segment of ``j``, moved into ``i``'s frame, matches it with the lines compared
    in Hesse form in ``i``'s frame (``|d rho| <= strict_distance``). A pair scores the
    mean of its two directions' repeated length over trial length; the log, the mean over
    pairs (``strict``) and the mean repeated metres per scan and direction
    (``repeated_metres``); also the number of pairs scored.
    """
    hesse = replace(tol, distance_at="origin", distance=tol.strict_distance)
    scores, metres = [], []
    for pair in pairs:
        if not pair.used:
            continue
        ratios, repeated_lengths = [], []
        for mine, theirs, pose, other in (
            (ends[pair.i], ends[pair.j], pair.pose, scans[pair.j]),
            (ends[pair.j], ends[pair.i], invert(pair.pose), scans[pair.i]),
        ):
            trial, repeated = _direction(
                mine, _moved(theirs, pose), invert(pose), other, tol, hesse
            )
            repeated_lengths.append(repeated)
            if trial > 0:
                ratios.append(repeated / trial)
        metres.append(float(np.mean(repeated_lengths)))
        if ratios:
            scores.append(float(np.mean(ratios)))
    return (
        float(np.mean(scores)) if scores else math.nan,
        float(np.mean(metres)) if metres else math.nan,
        len(scores),
    )


def _direction(mine, theirs, to_other, other, tol, hesse) -> tuple[float, float]:
    """Trial and repeated length of one direction of a pair (see :func:`_strict_scores`)."""
    lengths = np.hypot(*(mine[:, 2:4] - mine[:, 0:2]).T) if len(mine) else np.zeros(0)
    long = np.flatnonzero(np.isfinite(lengths) & (lengths >= tol.min_length))
    if len(long) == 0:
        return 0.0, 0.0
    share = np.linspace(0.0, 1.0, SURFACE_SAMPLES)[:, None]
    observed = np.zeros(len(long), dtype=bool)
    for k, m in enumerate(long):
        samples = mine[m, 0:2] + share * (mine[m, 2:4] - mine[m, 0:2])
        moved = transform_points(samples, to_other)
        observed[k] = _share_in_view(moved, other, tol.occlusion_margin) >= 0.5
    long = long[observed]
    if len(long) == 0:
        return 0.0, 0.0
    hit = match_segments(mine[long], theirs, hesse).any(axis=1)
    return float(lengths[long].sum()), float(lengths[long][hit].sum())


def _ratio(a: float, b: float) -> float:
    return a / b if b else math.nan
