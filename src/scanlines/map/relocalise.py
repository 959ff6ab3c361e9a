"""Global localisation on a line map: pose hypotheses from a scan's segments, kept when scans agree.

::

    from scanlines.map.relocalise import GlobalSearch

    search = GlobalSearch(tracker)              # a LineMapFilter on the map
    search.explained(points, pose)              # share of returns near a map line
    search.propose(scan, odometry_state)        # hypotheses from the scan's segments
    search.step(points, increment)              # each scan: hypotheses tracked and scored
    search.winner()                             # the hypothesis scans agreed on, or None

Two scan segments that are not parallel, matched to two map lines whose angle between them
is the same, fix a pose: the turn from the angles, the position from the two lines' offsets
(the sensor on a side each map line was seen from, each segment overlapping its map line).
Every such pair of the scan's longest segments against every pair of map lines gives the
candidates; each is scored by the share of the scan's returns within ``near`` of a map
line (:class:`ExplainedGrid`: a bitmap of the cells near the map's lines), and the best
distinct ones become hypotheses. Each hypothesis is then a copy of the filter (with the
odometry's errors learnt so far), stepped on the next scans like the filter itself and
scored again on each; a hypothesis is kept when it has explained at least ``found_share``
of the returns over ``agree`` scans and no distinct rival comes within ``margin`` of it.
Where the map holds only part of what the sensor sees, a hypothesis leading its rivals may
instead be judged where the map has lines (:func:`~scanlines.map.scoring.mapped`: its beams
cast on the map's lines over ``agree_far`` scans, few seen through a wall, most of those
that meet a map line explained).
"""

from __future__ import annotations

import copy
import math
from collections import deque

import numpy as np

from scanlines.geometry.poses import Pose, compose
from scanlines.map.scoring import ExplainedGrid, beam_shares, mapped
from scanlines.map.search_settings import SearchSettings

__all__ = ["ExplainedGrid", "GlobalSearch", "Hypothesis", "LinePairs", "SearchSettings",
           "pose_candidates"]  # fmt: skip


def _wrap(angle):
    return np.mod(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


def _segments(segments: np.ndarray, settings: SearchSettings) -> np.ndarray:
    """The longest of a scan's segments (rows: rho, alpha, start x, y, end x, y)."""
    length = np.hypot(segments[:, 4] - segments[:, 2], segments[:, 5] - segments[:, 3])
    keep = np.flatnonzero(length >= settings.min_segment)
    keep = keep[np.argsort(-length[keep])][: settings.segments]
    return segments[keep]


class LinePairs:
    """The pairs ``(a, b)`` of map lines (both orders) that could fix a pose: each at least
    ``min_line`` long, crossing at ``min_crossing`` or more, within ``max_pair_distance`` of
    each other; sorted by the angle from ``a`` to ``b`` (mod pi, in [-pi/2, pi/2))."""

    def __init__(self, lines, settings: SearchSettings) -> None:
        start, end = np.asarray(lines.start), np.asarray(lines.end)
        alpha = np.asarray(lines.alpha)
        usable = np.flatnonzero(np.hypot(*(end - start).T) >= settings.min_line)
        lo = np.minimum(start, end)[usable]
        hi = np.maximum(start, end)[usable]
        pairs_a, pairs_b, gaps = [], [], []
        for k, line in enumerate(usable):  # one row at a time: memory follows the pairs kept
            gap = np.maximum(0.0, np.maximum(lo - hi[k], lo[k] - hi))
            distance = np.hypot(gap[:, 0], gap[:, 1])
            between = _half_turn(alpha[usable] - alpha[line])
            keep = (distance <= settings.max_pair_distance) & (
                np.abs(between) >= settings.min_crossing
            )
            pairs_a.append(np.full(int(keep.sum()), line, dtype=np.int32))
            pairs_b.append(usable[keep].astype(np.int32))
            gaps.append(distance[keep].astype(np.float32))
        a = np.concatenate(pairs_a) if pairs_a else np.zeros(0, np.int32)
        b = np.concatenate(pairs_b) if pairs_b else np.zeros(0, np.int32)
        gap = np.concatenate(gaps) if gaps else np.zeros(0, np.float32)
        between = _half_turn(alpha[b] - alpha[a]).astype(np.float32)
        order = np.argsort(between, kind="stable")
        self.a, self.b, self.between, self.gap = a[order], b[order], between[order], gap[order]
        self.length = np.hypot(*(end - start).T).astype(np.float32)

    def matching(
        self, crossing: float, tolerance: float, gap: float, lengths: tuple[float, float]
    ) -> tuple[np.ndarray, np.ndarray]:
        """The pairs whose angle is within ``tolerance`` of ``crossing`` (mod pi), whose
        boxes lie at most ``gap`` apart (two segments' lines are no farther apart than
        the segments) and whose lines are at least ``lengths`` long."""
        picks = []
        for centre in (crossing - math.pi, crossing, crossing + math.pi):
            lo = np.searchsorted(self.between, centre - tolerance, side="left")
            hi = np.searchsorted(self.between, centre + tolerance, side="right")
            if hi > lo:
                picks.append(np.arange(lo, hi))
        if not picks:
            return self.a[:0], self.b[:0]
        k = np.concatenate(picks)
        a, b = self.a[k], self.b[k]
        keep = (
            (self.gap[k] <= gap) & (self.length[a] >= lengths[0]) & (self.length[b] >= lengths[1])
        )
        return a[keep].astype(np.intp), b[keep].astype(np.intp)


def _half_turn(angle):
    """An angle between two lines (mod pi), in [-pi/2, pi/2)."""
    return np.mod(np.asarray(angle) + math.pi / 2, math.pi) - math.pi / 2


def pose_candidates(segments: np.ndarray, lines, pairs: LinePairs, settings: SearchSettings):
    """Poses (H x 3) that put two non-parallel ``segments`` (sensor frame; rows rho,
    alpha, start x, y, end x, y) on two map ``lines`` (a LineSet, with ``sides``) of
    ``pairs``, each segment overlapping its line and the sensor on a side each line was
    seen from."""
    rho, alpha = np.asarray(lines.rho), np.asarray(lines.alpha)
    sides = np.full(len(rho), 3) if lines.sides is None else np.asarray(lines.sides)
    out = []
    segments = _segments(segments, settings)
    for i in range(len(segments)):
        for j in range(i + 1, len(segments)):
            crossing = float(_half_turn(segments[j, 1] - segments[i, 1]))
            if abs(crossing) < settings.min_crossing:
                continue
            a, b = pairs.matching(
                crossing, settings.angle_tolerance, _apart(segments[i], segments[j]) + 0.5,
                (_length(segments[i]) - 2 * settings.overlap_slack,
                 _length(segments[j]) - 2 * settings.overlap_slack),
            )  # fmt: skip
            for flip in (0.0, math.pi):
                theta = _wrap(alpha[a] - segments[i, 1] + flip)
                poses = _solve(segments[i], segments[j], theta, a, b, rho, alpha)
                good = _fits(segments[i], poses, a, lines, sides, settings)
                poses, on = poses[good], b[good]
                out.append(poses[_fits(segments[j], poses, on, lines, sides, settings)])
    return np.concatenate(out) if out else np.zeros((0, 3))


def _length(segment) -> float:
    return math.hypot(segment[4] - segment[2], segment[5] - segment[3])


def _apart(p, q) -> float:
    """The distance between two segments' boxes (rows: rho, alpha, start, end)."""
    lo_p, hi_p = np.minimum(p[2:4], p[4:6]), np.maximum(p[2:4], p[4:6])
    lo_q, hi_q = np.minimum(q[2:4], q[4:6]), np.maximum(q[2:4], q[4:6])
    gap = np.maximum(0.0, np.maximum(lo_q - hi_p, lo_p - hi_q))
    return float(np.hypot(*gap))


def _solve(seg_i, seg_j, theta, a, b, rho, alpha) -> np.ndarray:
    """The positions that put ``seg_i`` on lines ``a`` and ``seg_j`` on lines ``b`` at
    headings ``theta``."""
    ni = np.stack((np.cos(seg_i[1] + theta), np.sin(seg_i[1] + theta)), axis=-1)
    nj = np.stack((np.cos(seg_j[1] + theta), np.sin(seg_j[1] + theta)), axis=-1)
    na = np.stack((np.cos(alpha[a]), np.sin(alpha[a])), axis=-1)
    nb = np.stack((np.cos(alpha[b]), np.sin(alpha[b])), axis=-1)
    sa = np.sign(np.sum(ni * na, axis=1))
    sb = np.sign(np.sum(nj * nb, axis=1))
    ra, rb = sa * rho[a] - seg_i[0], sb * rho[b] - seg_j[0]
    det = ni[:, 0] * nj[:, 1] - ni[:, 1] * nj[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (ra * nj[:, 1] - rb * ni[:, 1]) / det
        y = (ni[:, 0] * rb - nj[:, 0] * ra) / det
    return np.column_stack((x, y, theta))


def _fits(segment, poses, line_ids, lines, sides, settings: SearchSettings) -> np.ndarray:
    """Whether ``segment`` at each of ``poses`` overlaps its map line and the sensor is on
    a side that line was seen from."""
    alpha = np.asarray(lines.alpha)[line_ids]
    rho = np.asarray(lines.rho)[line_ids]
    x, y, t = poses[:, 0], poses[:, 1], poses[:, 2]
    offset = np.cos(alpha) * x + np.sin(alpha) * y - rho
    side = np.where(offset > 0, 1, 2)
    ok = np.isfinite(x) & ((sides[line_ids] & side) != 0)
    if not ok.any():
        return ok
    tangent = np.stack((-np.sin(alpha), np.cos(alpha)), axis=-1)
    ends = []
    for px, py in (segment[2:4], segment[4:6]):
        wx = x + np.cos(t) * px - np.sin(t) * py
        wy = y + np.sin(t) * px + np.cos(t) * py
        ends.append(tangent[:, 0] * wx + tangent[:, 1] * wy)
    lo, hi = np.minimum(*ends), np.maximum(*ends)
    start, end = np.asarray(lines.start)[line_ids], np.asarray(lines.end)[line_ids]
    a = np.sum(tangent * start, axis=1)
    b = np.sum(tangent * end, axis=1)
    slack = settings.overlap_slack
    ok &= (lo >= np.minimum(a, b) - slack) & (hi <= np.maximum(a, b) + slack)
    return ok


def _distinct(poses: np.ndarray, scores: np.ndarray, settings: SearchSettings, count: int):
    """The best ``count`` of ``poses`` by ``scores``, each distinct from the better ones."""
    kept: list[int] = []
    for k in np.argsort(-scores, kind="stable"):
        if len(kept) >= count:
            break
        if all(not _same(poses[k], poses[q], settings) for q in kept):
            kept.append(int(k))
    return kept


def _same(p, q, settings: SearchSettings) -> bool:
    return (
        math.hypot(p[0] - q[0], p[1] - q[1]) < settings.distinct_distance
        and abs(float(_wrap(p[2] - q[2]))) < settings.distinct_angle
    )


class Hypothesis:
    """A pose hypothesis: a copy of the filter, the odometry's move since its last step
    (it is stepped every ``refine_every`` scans, dead-reckoned between), and the shares
    of returns it explained, scan by scan."""

    def __init__(self, tracker) -> None:
        self.tracker = tracker
        self.pending: Pose = (0.0, 0.0, 0.0)
        self.shares: list[float] = []
        self.crossed: list[float] = []  # shares of beams through a map line, when checked
        self.poses: list[Pose] = []  # its pose at each share
        self.beams: dict[int, tuple[float, float]] = {}  # beam_shares by the search's scan
        self.pose: Pose = self._pose()

    def _pose(self) -> Pose:
        return compose(tuple(float(v) for v in self.tracker.state[:3]), self.pending)

    def move(self, increment: Pose | None, points: np.ndarray | None) -> None:
        """Moved by the odometry ``increment``; stepped through the filter on ``points``
        (sensor-frame returns) when given."""
        if increment is not None:
            self.pending = compose(self.pending, increment)
        if points is not None:
            self.tracker.step(points, None if self.pending == (0.0, 0.0, 0.0) else self.pending)
            self.pending = (0.0, 0.0, 0.0)
        self.pose = self._pose()

    def recent(self, count: int) -> float:
        last = self.shares[-count:]
        return sum(last) / len(last) if last else 0.0


class GlobalSearch:
    """Hypotheses on the map of ``tracker`` (a :class:`~scanlines.map.filter.
    LineMapFilter`, whose lines and settings the hypotheses share)."""

    def __init__(self, tracker, settings: SearchSettings | None = None, extractor=None) -> None:
        self.settings = settings or SearchSettings()
        self.tracker = tracker
        self._extractor = extractor
        lines = tracker.lines
        self.grid = ExplainedGrid(lines.start, lines.end, self.settings.near, self.settings.cell)
        self._pairs: LinePairs | None = None
        self.hypotheses: list[Hypothesis] = []
        self._scans = 0
        self._picks: dict[int, np.ndarray] = {}  # the returns scored, by the scan's size
        self._samples: deque[np.ndarray] = deque(maxlen=self.settings.agree_far)

    @property
    def pairs(self) -> LinePairs:
        """The map's line pairs, made the first time a pose is searched for."""
        if self._pairs is None:
            self._pairs = LinePairs(self.tracker.lines, self.settings)
        return self._pairs

    def sample(self, points: np.ndarray) -> np.ndarray:
        """The returns scored (evenly subsampled)."""
        count = self.settings.score_points
        if len(points) <= count:
            return points
        picks = self._picks.get(len(points))
        if picks is None:
            picks = np.linspace(0, len(points) - 1, count).round().astype(np.intp)
            self._picks[len(points)] = picks
        return points[picks]

    def explained(self, points: np.ndarray, pose: Pose) -> float:
        """The share of the scan's returns within ``near`` of a map line at ``pose``."""
        return self.grid.share_at(self.sample(points), pose)

    def propose(self, scan, points: np.ndarray, errors=None) -> int:
        """New hypotheses from ``scan``'s segments (``points``: its valid returns, sensor
        frame; ``errors``: the odometry's errors and their covariance to start them with,
        ``state[3:]`` of the filter and its block); how many."""
        from scanlines.extractor import Extractor

        s = self.settings
        if self._extractor is None:
            self._extractor = Extractor()
        rows = np.asarray(self._extractor(scan).lines)[:, :6]
        poses = pose_candidates(rows, self.tracker.lines, self.pairs, s)
        if not len(poses):
            return 0
        sample = self.sample(points)
        scores = self.grid.shares(sample, poses)
        added = 0
        for k in _distinct(poses, scores, s, s.candidates):
            if scores[k] < s.drop_share:
                break
            if any(_same(poses[k], h.pose, s) for h in self.hypotheses):
                continue
            hypothesis = self._hypothesis(poses[k], errors)
            hypothesis.move(None, points)  # aligned on the scan it came from
            hypothesis.shares.append(float(self.grid.shares(sample, hypothesis.pose)[0]))
            hypothesis.poses.append(hypothesis.pose)
            self.hypotheses.append(hypothesis)
            added += 1
        self._trim()
        return added

    def _hypothesis(self, pose, errors) -> Hypothesis:
        s = self.settings
        tracker = copy.copy(self.tracker)
        tracker.start(tuple(float(v) for v in pose), (s.sigma_xy, s.sigma_theta))
        if errors is not None:
            tracker.state[3:] = errors[0]
            tracker.covariance[3:, 3:] = errors[1]
        return Hypothesis(tracker)

    def step(self, points: np.ndarray, increment: Pose | None, tracked: bool = False) -> None:
        """Each hypothesis moved by the odometry (stepped through its filter every
        ``refine_every`` scans, ``refine_every_tracked`` while the filter still has a pose
        of its own: a long search there is mostly a place the map lacks) and scored on the
        scan (sensor-frame returns); the poor and the duplicates dropped."""
        s = self.settings
        self._scans += 1
        self._samples.append(self.sample(points))
        refine = self._scans % (s.refine_every_tracked if tracked else s.refine_every) == 0
        for h in self.hypotheses:
            h.move(increment, points if refine else None)
        if self.hypotheses:
            poses = np.array([h.pose for h in self.hypotheses])
            shares = self.grid.shares(self.sample(points), poses)
            for h, share in zip(self.hypotheses, shares, strict=True):
                h.shares.append(float(share))
                h.poses.append(h.pose)
        kept: list[Hypothesis] = []
        for h in sorted(self.hypotheses, key=lambda h: -len(h.shares)):
            if len(h.shares) >= s.drop_after and h.recent(s.drop_after) < s.drop_share:
                continue
            if refine and any(_same(h.pose, k.pose, s) for k in kept):
                continue  # two that became one (checked when they are refined)
            kept.append(h)
        self.hypotheses = kept

    def _mapped(self, h: Hypothesis) -> bool:
        """:func:`~scanlines.map.scoring.mapped` over the last ``agree_far`` scans, the beams
        cast only for a hypothesis explaining ``mapped_share`` (the costly part)."""
        s = self.settings
        count = s.agree_far
        if len(h.shares) < count or len(self._samples) < count:
            return False
        if h.recent(count) < s.mapped_share:
            return False
        beams = []
        for back in range(1, count + 1):
            scan = self._scans - back + 1
            if scan not in h.beams:
                sample, pose = self._samples[-back], h.poses[-back]
                explained = self.grid.hits_at(sample, pose)
                h.beams[scan] = beam_shares(
                    sample, pose, explained, self.tracker.lines, s.clearance, s.reach
                )
            beams.append(h.beams[scan])
        for old in [k for k in h.beams if k <= self._scans - count]:
            del h.beams[old]
        return mapped(h.shares, beams[::-1], count, s)

    def _trim(self) -> None:
        s = self.settings
        if len(self.hypotheses) > s.max_hypotheses:
            self.hypotheses.sort(key=lambda h: -h.recent(s.agree))
            del self.hypotheses[s.max_hypotheses :]

    def winner(self, points: np.ndarray, rival: float = 0.0, near=None) -> Hypothesis | None:
        """The hypothesis the last scans agree on: one ``near`` the filter's own pose
        (``near()`` gives the test of a pose; none: no pose yet) after ``agree`` scans explaining
        ``found_share`` of the returns, one farther after ``agree_far`` scans explaining
        ``found_share_far``; neither another distinct hypothesis nor ``rival`` (the
        filter's own share over the same scans) came within ``margin`` of it; and at most
        ``max_crossed`` of the scan's returns (``points``) were seen through a map line
        from it (else it is dropped)."""
        s = self.settings
        best, best_score = None, -1.0
        if near is not None and any(len(h.shares) >= s.agree for h in self.hypotheses):
            near = near()  # the filter's uncertainty, worked out when a hypothesis is ready
        for h in self.hypotheses:
            if len(h.shares) < s.agree:
                continue
            close = near is not None and near(h.pose)
            count, floor = (s.agree, s.found_share) if close else (s.agree_far, s.found_share_far)
            if len(h.shares) < count:
                continue
            score = h.recent(count)
            if score < rival + s.margin or score <= best_score:
                continue
            if score >= floor or (self._leads(h) and self._mapped(h)):
                best, best_score = h, score
        if best is None or not self._leads(best):
            return None
        if self._mapped(best):
            return best  # its beams cast on the map's lines: none seen through a wall
        best.crossed.append(self.grid.crossed(self.sample(points), best.pose, s.clearance, s.reach))
        if len(best.crossed) < s.checks or np.mean(best.crossed[-s.checks :]) > s.max_crossed:
            return None
        return best

    def _leads(self, best: Hypothesis) -> bool:
        """Whether no hypothesis distinct from ``best`` comes within ``margin`` of it over
        the last ``agree`` scans."""
        s = self.settings
        lead = best.recent(s.agree) - s.margin
        return not any(
            h is not best and h.recent(s.agree) > lead and not _same(h.pose, best.pose, s)
            for h in self.hypotheses
        )

    def settle(self, winner: Hypothesis) -> None:
        """The winner's pending move applied through its filter (no returns matched)."""
        if winner.pending != (0.0, 0.0, 0.0):
            winner.move(None, np.zeros((0, 2)))

    def clear(self) -> None:
        self.hypotheses = []
        self._scans = 0
        self._samples.clear()
