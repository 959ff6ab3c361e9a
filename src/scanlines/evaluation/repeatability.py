"""Scan-to-scan repeatability on real logs, without labels: :func:`repeatability`.

A good extractor finds the same wall in the next scans of a log. The measure::

    from scanlines.evaluation.repeatability import repeatability

    result = repeatability("fr079.log.gz", ["adaptive", "iepf"], max_scans=300)
    result.table()                      # formatted rows, one per method spec
    write_results([result], "out/")     # repeatability.csv, repeatability_pairs.csv, .json

Pairs
-----
Scan ``i`` is paired with each scan ``j`` 1 to ``max_gap`` (3) records later (record
numbers of the log). Their relative pose (``j``'s sensor frame in ``i``'s) is refined by
the point-to-line ICP of :mod:`scanlines.evaluation.registration`, starting from the
relative pose of the log's poses when both scans have one. A log without poses is
registered by ICP alone: ``(i, i + 1)`` from the identity and from the previous
consecutive estimate (constant velocity), keeping the fit with more inliers;
``(i, i + k)`` from the chain of the refined consecutive poses.

The *view overlap* of a pair is the smaller of two shares: of ``j``'s valid returns
that, moved into ``i``'s frame, fall inside ``i``'s field of view and range limits and
are not hidden behind ``i``'s own returns (farther than the largest range of the three
nearest beams of ``i`` plus ``occlusion_margin``), and the same of ``i``'s returns in
``j``. A pair is *used* when its view overlap is at least ``view_overlap`` (0.5) and its
registration has at least ``min_inliers`` (0.5) of ``j``'s returns within
``inlier_residual`` of ``i``'s local lines (see :class:`~.registration.Registration`).

Matching
--------
``j``'s segments are moved into ``i``'s frame with the refined pose. A segment ``s`` of
``i`` (start ``a``, unit direction ``u``, length ``L``) and a segment ``t`` of ``j``
match when all three hold:

* angle: the undirected angle between their directions is at most ``alpha`` (2 deg);
* overlap: project ``t``'s endpoints onto ``s``'s line, ``[lo, hi]`` along ``u`` from
  ``a``; ``overlap = |[lo, hi] & [0, L]| / min(L, hi - lo)`` is at least ``overlap``
  (0.5), the shorter length being ``t``'s projected length;
* distance: the point of ``t`` above the middle of that common interval is within
  ``distance`` (3 cm) of ``s``'s line (orthogonal distance; for straight segments it is
  the mean of the signed distances of the clipped endpoints: the Hesse-form offset at
  the place the two segments share, not at the origin). ``distance_at="origin"``
  compares ``|drho|`` of the two lines in Hesse form in ``i``'s frame instead (stricter
  for segments far from the foot of their normal; a sensitivity check).

Scores (per method spec)
------------------------
* ``repeatability``: a *long* segment (``min_length``, 0.5 m) of a scan with at least
  one used pair counts as repeated when a segment of any of its used partner scans
  matches it; repeated long segments over long segments of scans with a used pair;
* ``per_pair``: the same counted per (long segment, used pair): matches over trials;
* ``coverage``: valid returns inside a segment's beam interval (outliers excluded) over
  valid returns, pooled over all scans;
* ``median_length`` of all segments with a line (metres; ``unfitted`` counts the
  segments whose line is NaN, which match nothing: the paper preset returns many on
  3-return runs); ``short_share``: segments fitted to fewer than ``few_points`` (5) returns
  over all segments; ``per_scan``: segments per scan;
* ``per_metre``: segments over *surface length*, the length of the polyline through
  consecutive valid returns (beam order) that both lie on segments, without the steps
  that cross a breakpoint the method reported (depth gaps); steps at corners count.
  Unlike segments over the summed segment length (1 / mean length), it does not fall
  when a method covers the surface with fewer, longer segments only by leaving returns
  out.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.registration import (
    IDENTITY,
    IcpSettings,
    LineTarget,
    Pose,
    Registration,
    compose,
    icp,
    invert,
    line_target,
    relative_pose,
    transform_points,
)
from scanlines.evaluation.report import number, write_csv
from scanlines.evaluation.specs import MethodSpec, parse_specs
from scanlines.extraction import END_X, END_Y, START_X, START_Y
from scanlines.json_values import jsonable
from scanlines.sensor_profile import ProfileError, SensorProfile, estimate_profile

__all__ = [
    "TABLE_COLUMNS",
    "MethodRepeatability",
    "PairRecord",
    "RepeatTolerances",
    "RepeatabilityResult",
    "candidate_pairs",
    "match_segments",
    "register_pairs",
    "repeatability",
    "repeatability_of_scans",
    "view_overlap",
    "write_results",
]

OnProgress = Callable[[int, int], None]


@dataclass(frozen=True)
class RepeatTolerances:
    """What counts: pairs, long segments, matches (metres, radians, shares, records)."""

    min_length: float = 0.5
    alpha: float = math.radians(2.0)
    distance: float = 0.03
    distance_at: str = "overlap"
    overlap: float = 0.5
    view_overlap: float = 0.5
    min_inliers: float = 0.5
    max_gap: int = 3
    few_points: int = 5
    occlusion_margin: float = 0.2
    max_pairs: int | None = None
    strict_distance: float = 0.03

    def to_dict(self) -> dict[str, Any]:
        """The tolerances by name, with ``alpha_deg``."""
        return asdict(self) | {"alpha_deg": math.degrees(self.alpha)}

    def caption(self) -> str:
        """One line stating the definition, for table captions."""
        return (
            f"long segments >= {self.min_length:g} m of scan i vs segments of scans "
            f"i+1..i+{self.max_gap} moved by ICP; match: angle <= "
            f"{math.degrees(self.alpha):g} deg, line distance at the shared middle <= "
            f"{100 * self.distance:g} cm, overlap / shorter >= {self.overlap:g}; pairs used: "
            f"view overlap >= {self.view_overlap:g}, ICP inliers >= {self.min_inliers:g}"
        )


# --------------------------------------------------------------------------- pairs


@dataclass(frozen=True)
class PairRecord:
    """One candidate pair of scans and its registration.

    Attributes
    ----------
    i, j:
        Record numbers of the two scans (``j`` later).
    initial, pose:
        Relative pose of ``j`` in ``i`` before and after ICP.
    rms, inlier_fraction, iterations, converged:
        The registration's quality (:class:`~.registration.Registration`).
    view_overlap:
        The view overlap with the refined pose.
    used:
        Whether the pair counts (view overlap and inliers at least their thresholds).
    """

    i: int
    j: int
    initial: Pose
    pose: Pose
    rms: float
    inlier_fraction: float
    iterations: int
    converged: bool
    view_overlap: float
    used: bool

    @property
    def motion(self) -> tuple[float, float]:
        """Translation (metres) and absolute rotation (radians) of the refined pose."""
        return math.hypot(self.pose[0], self.pose[1]), abs(self.pose[2])

    @property
    def correction(self) -> tuple[float, float]:
        """How far ICP moved the initial guess: translation (metres), rotation (radians)."""
        dx, dy, dt = (a - b for a, b in zip(self.pose, self.initial, strict=True))
        return math.hypot(dx, dy), abs(math.remainder(dt, 2.0 * math.pi))

    def to_dict(self) -> dict[str, Any]:
        """Flat row for CSV."""
        move, turn = self.motion
        fix, fix_turn = self.correction
        return {
            "i": self.i,
            "j": self.j,
            "x": self.pose[0],
            "y": self.pose[1],
            "theta_deg": math.degrees(self.pose[2]),
            "initial_x": self.initial[0],
            "initial_y": self.initial[1],
            "initial_theta_deg": math.degrees(self.initial[2]),
            "motion_m": move,
            "turn_deg": math.degrees(turn),
            "icp_correction_m": fix,
            "icp_correction_deg": math.degrees(fix_turn),
            "icp_rms_m": self.rms,
            "icp_inliers": self.inlier_fraction,
            "icp_iterations": self.iterations,
            "icp_converged": self.converged,
            "view_overlap": self.view_overlap,
            "used": self.used,
        }


def _share_in_view(points: np.ndarray, scan: Scan, margin: float) -> float:
    """Share of ``points`` (in ``scan``'s frame) inside its view and not hidden behind it."""
    if len(points) == 0:
        return 0.0
    n, step = len(scan), abs(scan.angle_increment)
    r = np.hypot(points[:, 0], points[:, 1])
    # Beam coordinate of each bearing, counted from beam 0 the way the beams turn.
    turn = (np.arctan2(points[:, 1], points[:, 0]) - scan.angle_min) * np.sign(scan.angle_increment)
    k = np.mod(turn, 2.0 * math.pi) / step
    if scan.full_circle:
        inside = np.ones(len(points), dtype=bool)
        nearest = np.rint(k).astype(np.intp) % n
    else:
        inside = (k <= n - 0.5) | (k >= 2.0 * math.pi / step - 0.5)
        nearest = np.where(k <= n - 0.5, np.rint(k), 0).astype(np.intp)
    inside &= (r >= scan.range_min) & (r <= scan.range_max)
    measured = np.where(scan.valid, scan.ranges, -np.inf)
    farthest = np.max(np.stack([measured[(nearest + d) % n] for d in (-1, 0, 1)], axis=1), axis=1)
    hidden = np.isfinite(farthest) & (r > farthest + margin)
    return float(np.count_nonzero(inside & ~hidden) / len(points))


def view_overlap(scan_i: Scan, scan_j: Scan, pose: Sequence[float], margin: float = 0.2) -> float:
    """The smaller share of either scan's returns that lie in the other's view.

    ``pose`` is ``j``'s frame in ``i``'s. A return lies in a scan's view when it is inside
    the field of view and the range limits and not more than ``margin`` behind the
    farthest of the three nearest beams' returns.
    """
    pj = transform_points(scan_j.points[scan_j.valid], pose)
    pi = transform_points(scan_i.points[scan_i.valid], invert(pose))
    return min(_share_in_view(pj, scan_i, margin), _share_in_view(pi, scan_j, margin))


def _better(a: Registration, b: Registration) -> Registration:
    if a.n_inliers != b.n_inliers:
        return a if a.n_inliers > b.n_inliers else b
    return a if (a.rms if math.isfinite(a.rms) else math.inf) <= b.rms else b


def register_pairs(
    scans: Sequence[tuple[int, Scan]],
    tol: RepeatTolerances | None = None,
    settings: IcpSettings | None = None,
    on_pair: OnProgress | None = None,
) -> tuple[tuple[PairRecord, ...], str]:
    """Every candidate pair of ``scans`` (``(record, scan)`` in log order), registered.

    Returns the pairs and the pose source: ``"log poses + ICP"`` when every scan has a
    pose, else ``"ICP alone"`` (see the module docstring for the initial guesses).
    """
    tol = tol or RepeatTolerances()
    settings = settings or IcpSettings()
    with_poses = all(scan.pose is not None for _, scan in scans)
    targets: dict[int, LineTarget] = {}
    sources: dict[int, np.ndarray] = {}
    for index, scan in scans:
        targets[index] = line_target(scan, settings)
        sources[index] = scan.points[scan.valid]
    candidates = candidate_pairs(scans, tol)
    consecutive: dict[int, Pose] = {}  # record i -> refined pose of the next record in i
    previous: Pose | None = None
    pairs = []
    for done, (a, b) in enumerate(sorted(candidates, key=lambda ab: (ab[1] - ab[0], ab))):
        (i, scan_i), (j, scan_j) = scans[a], scans[b]
        if with_poses:
            fit = icp(sources[j], targets[i], relative_pose(scan_i.pose, scan_j.pose), settings)
        elif b == a + 1:
            fit = icp(sources[j], targets[i], IDENTITY, settings)
            if previous is not None:
                fit = _better(fit, icp(sources[j], targets[i], previous, settings))
            previous = fit.pose if fit.inlier_fraction >= tol.min_inliers else None
            consecutive[i] = fit.pose
        else:
            chain = IDENTITY
            for step in range(a, b):
                chain = compose(chain, consecutive.get(scans[step][0], IDENTITY))
            fit = icp(sources[j], targets[i], chain, settings)
        overlap = view_overlap(scan_i, scan_j, fit.pose, tol.occlusion_margin)
        used = overlap >= tol.view_overlap and fit.inlier_fraction >= tol.min_inliers
        pairs.append(
            PairRecord(
                i,
                j,
                fit.initial,
                fit.pose,
                fit.rms,
                fit.inlier_fraction,
                fit.iterations,
                fit.converged,
                overlap,
                used,
            )
        )
        if on_pair is not None:
            on_pair(done + 1, len(candidates))
    pairs.sort(key=lambda p: (p.i, p.j))
    return tuple(pairs), "log poses + ICP" if with_poses else "ICP alone"


def candidate_pairs(scans: Sequence[tuple[int, Scan]], tol: RepeatTolerances) -> list:
    """Positions ``(a, b)`` of the pairs to register: every pair 1 to ``max_gap`` records
    apart, or with ``max_pairs`` that many spread evenly over the log (the gap cycling
    through 1 .. ``max_gap``), so that a long log costs no more than a short one."""
    every = [
        (a, b)
        for a in range(len(scans))
        for b in range(a + 1, min(a + 1 + tol.max_gap, len(scans)))
        if 1 <= scans[b][0] - scans[a][0] <= tol.max_gap
    ]
    if tol.max_pairs is None or len(every) <= tol.max_pairs:
        return every
    by_start: dict[int, list[tuple[int, int]]] = {}
    for a, b in every:
        by_start.setdefault(a, []).append((a, b))
    starts = sorted(by_start)
    chosen = []
    for k in range(tol.max_pairs):
        options = by_start[starts[k * len(starts) // tol.max_pairs]]
        chosen.append(options[k % len(options)])
    return chosen


# --------------------------------------------------------------------------- matching


def match_segments(
    ends_i: np.ndarray, ends_j: np.ndarray, tol: RepeatTolerances | None = None
) -> np.ndarray:
    """``M x K`` booleans: segment ``m`` of ``i`` matches segment ``k`` of ``j``.

    ``ends_*`` are ``N x 4`` arrays ``start x, start y, end x, end y``, both in ``i``'s
    frame. The three conditions are those of the module docstring.
    """
    tol = tol or RepeatTolerances()
    ends_i = np.asarray(ends_i, dtype=np.float64).reshape(-1, 4)
    ends_j = np.asarray(ends_j, dtype=np.float64).reshape(-1, 4)
    if len(ends_i) == 0 or len(ends_j) == 0:
        return np.zeros((len(ends_i), len(ends_j)), dtype=bool)
    a = ends_i[:, None, 0:2]
    d_i = ends_i[:, 2:4] - ends_i[:, 0:2]
    length = np.hypot(d_i[:, 0], d_i[:, 1])[:, None]
    u = (d_i / np.maximum(length, 1e-12))[:, None, :]
    normal = np.concatenate((-u[..., 1:2], u[..., 0:1]), axis=-1)
    s, e = ends_j[None, :, 0:2], ends_j[None, :, 2:4]
    d_j = ends_j[:, 2:4] - ends_j[:, 0:2]
    u_j = d_j / np.maximum(np.hypot(d_j[:, 0], d_j[:, 1]), 1e-12)[:, None]
    cos = np.abs(np.sum(u * u_j[None, :, :], axis=-1))
    angle_ok = cos >= math.cos(tol.alpha)
    ps = np.sum((s - a) * u, axis=-1)
    pe = np.sum((e - a) * u, axis=-1)
    lo, hi = np.minimum(ps, pe), np.maximum(ps, pe)
    common_lo, common_hi = np.maximum(lo, 0.0), np.minimum(hi, length)
    common = np.maximum(common_hi - common_lo, 0.0)
    shorter = np.minimum(length, hi - lo)
    with np.errstate(invalid="ignore", divide="ignore"):
        overlap_ok = (shorter > 0) & (common / shorter >= tol.overlap)
        middle = (common_lo + common_hi) / 2.0
        # The point of t above `middle`: interpolate the signed distances of its ends.
        ds = np.sum((s - a) * normal, axis=-1)
        de = np.sum((e - a) * normal, axis=-1)
        along = np.where(pe != ps, (middle - ps) / (pe - ps), 0.5)
        distance = np.abs(ds + along * (de - ds))
    if tol.distance_at == "origin":  # Hesse form: |drho| of the two lines in i's frame
        rho_i = np.sum(a * normal, axis=-1)
        sign = np.where(np.sum(normal * np.stack((-u_j[:, 1], u_j[:, 0]), axis=-1), -1) < 0, -1, 1)
        n_j = sign[..., None] * np.stack((-u_j[:, 1], u_j[:, 0]), axis=-1)[None, :, :]
        distance = np.abs(np.sum(s * n_j, axis=-1) - rho_i)
    return angle_ok & overlap_ok & (distance <= tol.distance)


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
    """The scores of one method spec on one log (see the module docstring)."""

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


def _moved(ends: np.ndarray, pose: Pose) -> np.ndarray:
    if len(ends) == 0:
        return ends
    return np.column_stack(
        (transform_points(ends[:, 0:2], pose), transform_points(ends[:, 2:4], pose))
    )


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


# --------------------------------------------------------------------------- running


@dataclass(frozen=True, eq=False)
class RepeatabilityResult:
    """Pairs and per-method scores of one log.

    Attributes
    ----------
    log:
        The log's path as given.
    scans:
        Scans read (the first ``max_scans`` of the log, or all).
    pose_source:
        ``"log poses + ICP"`` or ``"ICP alone"``.
    pairs:
        Every candidate pair with its registration (:class:`PairRecord`).
    methods:
        One :class:`MethodRepeatability` per spec, in the order given.
    tol, icp:
        The tolerances and ICP settings used.
    """

    log: str
    scans: int
    pose_source: str
    pairs: tuple[PairRecord, ...]
    methods: tuple[MethodRepeatability, ...]
    tol: RepeatTolerances
    icp: IcpSettings

    @property
    def used_pairs(self) -> tuple[PairRecord, ...]:
        """The pairs that count."""
        return tuple(p for p in self.pairs if p.used)

    def pair_stats(self) -> dict[str, Any]:
        """Pair counts, and medians of motion and ICP quality over the used pairs."""
        used = self.used_pairs

        def median(values: list[float]) -> float:
            finite = [v for v in values if math.isfinite(v)]
            return float(np.median(finite)) if finite else math.nan

        return {
            "candidate_pairs": len(self.pairs),
            "used_pairs": len(used),
            "rejected_view": sum(p.view_overlap < self.tol.view_overlap for p in self.pairs),
            "rejected_icp": sum(
                p.view_overlap >= self.tol.view_overlap and p.inlier_fraction < self.tol.min_inliers
                for p in self.pairs
            ),
            "median_motion_m": median([p.motion[0] for p in used]),
            "median_turn_deg": median([math.degrees(p.motion[1]) for p in used]),
            "median_icp_correction_m": median([p.correction[0] for p in used]),
            "median_icp_correction_deg": median([math.degrees(p.correction[1]) for p in used]),
            "median_icp_rms_m": median([p.rms for p in used]),
            "median_icp_inliers": median([p.inlier_fraction for p in used]),
            "median_view_overlap": median([p.view_overlap for p in used]),
        }

    def summary_rows(self) -> list[dict[str, Any]]:
        """One row per method, with the log, pose source and used pairs."""
        head = {"log": self.log, "scans": self.scans, "pose_source": self.pose_source}
        pairs = {"pairs_used": len(self.used_pairs)}
        return [head | m.to_dict() | pairs for m in self.methods]

    def pair_rows(self) -> list[dict[str, Any]]:
        """One row per candidate pair, with the log."""
        return [{"log": self.log} | p.to_dict() for p in self.pairs]

    def to_dict(self) -> dict[str, Any]:
        """Log, settings, pair statistics and the summary rows; NaN becomes ``None``."""
        return jsonable(
            {
                "log": self.log,
                "scans": self.scans,
                "pose_source": self.pose_source,
                "tolerances": self.tol.to_dict(),
                "icp": self.icp.to_dict(),
                "pairs": self.pair_stats(),
                "methods": [m.spec.to_dict() for m in self.methods],
                "summary": self.summary_rows(),
            }
        )

    def title(self) -> str:
        """One line: the log, scans, pose source and pairs."""
        stats = self.pair_stats()
        return (
            f"{self.log}: {self.scans} scans, {self.pose_source}, {stats['used_pairs']} of "
            f"{stats['candidate_pairs']} pairs used ({stats['rejected_view']} view overlap, "
            f"{stats['rejected_icp']} ICP), median motion {number(stats['median_motion_m'])} "
            f"m / {number(stats['median_turn_deg'], '.1f')} deg, ICP rms "
            f"{number(100 * stats['median_icp_rms_m'], '.1f')} cm"
        )

    def table(self) -> list[list[str]]:
        """Formatted :data:`TABLE_COLUMNS` rows, one per method."""
        return [
            [m.spec.label, *(number(fn(m), fmt) for _, fn, fmt in TABLE_COLUMNS)]
            for m in self.methods
        ]


TABLE_COLUMNS: tuple[tuple[str, Callable[[MethodRepeatability], float], str], ...] = (
    ("strict", lambda m: m.strict, ".3f"),
    ("repeated m/scan", lambda m: m.repeated_metres, ".2f"),
    ("repeat.", lambda m: m.repeatability, ".3f"),
    ("per pair", lambda m: m.per_pair, ".3f"),
    ("coverage", lambda m: m.coverage, ".3f"),
    ("median m", lambda m: m.median_length, ".2f"),
    ("< 5 returns", lambda m: m.short_share, ".3f"),
    ("seg/scan", lambda m: m.per_scan, ".1f"),
    ("seg/m", lambda m: m.per_metre, ".3f"),
    ("long", lambda m: m.long_segments, "d"),
)
"""Table columns: header, value of a :class:`MethodRepeatability`, format."""

TABLE_CAPTION = (
    "strict: each used pair scored on its own, both directions averaged, length-weighted, "
    "lines compared in Hesse form (|d rho| at the origin), only long segments the other scan "
    "observed; repeated m/scan: metres of long segments repeated per scan and direction; "
    "repeat.: long segments repeated in any used later pair / long segments; per pair: the "
    "same per (segment, pair); coverage: valid returns on segments; median m: median segment "
    "length; < 5 returns: share of segments; seg/m: segments per metre of surface (polyline "
    "through consecutive returns on segments, not across breakpoints); long: long segments "
    "of scans with a used pair."
)


def repeatability_of_scans(
    scans: Iterable[tuple[int, Scan]],
    specs: Iterable[str | MethodSpec],
    *,
    log: str = "",
    tol: RepeatTolerances | None = None,
    settings: IcpSettings | None = None,
    on_progress: OnProgress | None = None,
    sensor_profile: SensorProfile | None = None,
) -> RepeatabilityResult:
    """Repeatability of ``specs`` on ``(record, scan)`` pairs in log order, every spec with
    ``sensor_profile`` (``None``: one measured from the scans, as ``scanlines run`` does)."""
    parsed = parse_specs(specs)
    tol = tol or RepeatTolerances()
    settings = settings or IcpSettings()
    scans = list(scans)
    profile = sensor_profile or _log_profile(scans, log)
    if tol.max_pairs is not None:  # only the scans of the chosen pairs are extracted
        chosen = {position for pair in candidate_pairs(scans, tol) for position in pair}
        scans = [scans[position] for position in sorted(chosen)]
    n_candidates = len(candidate_pairs(scans, tol))
    total = n_candidates + len(scans) * len(parsed)
    done = 0

    def tick(step: int = 1) -> None:
        nonlocal done
        done += step
        if on_progress is not None:
            on_progress(done, total)

    pairs, source = register_pairs(scans, tol, settings, on_pair=lambda _done, _total: tick())
    methods = tuple(_score_method(spec, scans, pairs, tol, tick, profile) for spec in parsed)
    return RepeatabilityResult(log, len(scans), source, pairs, methods, tol, settings)


def _log_profile(scans: Sequence[tuple[int, Scan]], log: str) -> SensorProfile | None:
    """The profile ``scanlines run`` would measure; ``None`` (each scan its own) when the
    scans hold too few returns on surfaces."""
    try:
        return estimate_profile((scan for _, scan in scans), source=log)
    except ProfileError:
        return None


def repeatability(
    log_path: str | Path,
    specs: Iterable[str | MethodSpec],
    max_scans: int | None = None,
    *,
    tol: RepeatTolerances | None = None,
    settings: IcpSettings | None = None,
    on_progress: OnProgress | None = None,
    sensor_profile: SensorProfile | None = None,
    **reader_options: Any,
) -> RepeatabilityResult:
    """Scan-to-scan repeatability of method specs on a log (any file ``open_log`` reads).

    Parameters
    ----------
    log_path:
        The log.
    specs:
        Method specs (:func:`~scanlines.evaluation.specs.parse_specs`); not ``truth``.
    max_scans:
        Read the first ``max_scans`` scans only (``None``: all).
    tol, settings:
        :class:`RepeatTolerances` and :class:`~.registration.IcpSettings`.
    sensor_profile:
        The profile every spec extracts with; ``None``: measured from the scans read.
    on_progress:
        Called with ``(done, total)`` after each pair registered and each scan extracted.
    **reader_options:
        Options of the log's reader (:func:`scanlines.io.open_log`).
    """
    from itertools import islice

    from scanlines.io import open_log

    reader = open_log(log_path, **reader_options)
    scans = list(islice(reader.enumerate(), max_scans))
    return repeatability_of_scans(
        scans, specs, log=str(log_path), tol=tol, settings=settings, on_progress=on_progress,
        sensor_profile=sensor_profile,
    )  # fmt: skip


def write_results(results: Sequence[RepeatabilityResult], directory: str | Path) -> list[Path]:
    """Write ``repeatability.csv`` (one row per log and method), ``repeatability_pairs.csv``
    (one row per candidate pair) and ``repeatability.json`` into ``directory``."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    summary = [row for r in results for row in r.summary_rows()]
    pairs = [row for r in results for row in r.pair_rows()]
    out = [
        write_csv(directory / "repeatability.csv", summary),
        write_csv(directory / "repeatability_pairs.csv", pairs),
    ]
    path = directory / "repeatability.json"
    path.write_text(json.dumps([r.to_dict() for r in results], indent=2) + "\n")
    return [*out, path]
