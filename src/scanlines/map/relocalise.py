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
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from scanlines.geometry.poses import Pose

__all__ = ["ExplainedGrid", "GlobalSearch", "Hypothesis", "SearchSettings", "pose_candidates"]


@dataclass(frozen=True)
class SearchSettings:
    """The constants of global localisation (metres, radians, shares of returns)."""

    near: float = 0.05
    cell: float = 0.025
    score_points: int = 60
    segments: int = 6
    min_segment: float = 0.6
    min_line: float = 0.5
    min_crossing: float = math.radians(30.0)
    angle_tolerance: float = math.radians(4.0)
    overlap_slack: float = 0.3
    candidates: int = 20
    distinct_distance: float = 0.5
    distinct_angle: float = math.radians(10.0)
    max_hypotheses: int = 40
    drop_share: float = 0.3
    agree: int = 10
    found_share: float = 0.6
    margin: float = 0.1
    lost_share: float = 0.25
    lost_after: int = 10
    propose_every: int = 5
    sigma_xy: float = 0.1
    sigma_theta: float = math.radians(3.0)


class ExplainedGrid:
    """A bitmap of the cells (``cell`` metres) within ``near`` of some map line: a return
    in such a cell is *explained* by the map."""

    def __init__(self, start: np.ndarray, end: np.ndarray, near: float, cell: float) -> None:
        start = np.asarray(start, dtype=np.float64).reshape(-1, 2)
        end = np.asarray(end, dtype=np.float64).reshape(-1, 2)
        self.cell = cell
        if not len(start):
            self.origin, self.bits = np.zeros(2), np.zeros((1, 1), dtype=bool)
            return
        self.origin = np.minimum(start, end).min(axis=0) - near - cell
        top = np.maximum(start, end).max(axis=0) + near + cell
        nx, ny = (int(v) for v in np.ceil((top - self.origin) / cell) + 1)
        self.bits = np.zeros((nx, ny), dtype=bool)
        reach = int(math.ceil(near / cell))
        di, dj = np.meshgrid(np.arange(-reach, reach + 1), np.arange(-reach, reach + 1))
        disk = np.hypot(di, dj) * cell <= near
        di, dj = di[disk], dj[disk]
        for a, b in zip(start, end, strict=True):
            count = max(2, int(math.ceil(np.hypot(*(b - a)) / (0.5 * cell))) + 1)
            t = np.linspace(0.0, 1.0, count)[:, None]
            cells = np.floor((a + t * (b - a) - self.origin) / cell).astype(np.int64)
            i = np.clip((cells[:, 0:1] + di).ravel(), 0, nx - 1)
            j = np.clip((cells[:, 1:2] + dj).ravel(), 0, ny - 1)
            self.bits[i, j] = True

    def shares(self, points: np.ndarray, poses: np.ndarray) -> np.ndarray:
        """The share of sensor-frame ``points`` (K x 2) explained at each of ``poses``
        (H x 3)."""
        poses = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
        if not len(points):
            return np.zeros(len(poses))
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        x = poses[:, 0:1] + c * points[:, 0] - s * points[:, 1]
        y = poses[:, 1:2] + s * points[:, 0] + c * points[:, 1]
        i = np.floor((x - self.origin[0]) / self.cell).astype(np.int64)
        j = np.floor((y - self.origin[1]) / self.cell).astype(np.int64)
        nx, ny = self.bits.shape
        inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        hit = np.zeros(i.shape, dtype=bool)
        hit[inside] = self.bits[i[inside], j[inside]]
        return hit.mean(axis=1)


def _wrap(angle):
    return np.mod(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


def _segments(segments: np.ndarray, settings: SearchSettings) -> np.ndarray:
    """The longest of a scan's segments (rows: rho, alpha, start x, y, end x, y)."""
    length = np.hypot(segments[:, 4] - segments[:, 2], segments[:, 5] - segments[:, 3])
    keep = np.flatnonzero(length >= settings.min_segment)
    keep = keep[np.argsort(-length[keep])][: settings.segments]
    return segments[keep]


def pose_candidates(segments: np.ndarray, lines, settings: SearchSettings) -> np.ndarray:
    """Poses (H x 3) that put two non-parallel ``segments`` (sensor frame; rows rho,
    alpha, start x, y, end x, y) on two map ``lines`` (a LineSet, with ``sides``), each
    segment overlapping its line and the sensor on a side each line was seen from."""
    rho, alpha = np.asarray(lines.rho), np.asarray(lines.alpha)
    start, end = np.asarray(lines.start), np.asarray(lines.end)
    sides = np.full(len(rho), 3) if lines.sides is None else np.asarray(lines.sides)
    length = np.hypot(*(end - start).T)
    usable = np.flatnonzero(length >= settings.min_line)
    out = []
    segments = _segments(segments, settings)
    for i in range(len(segments)):
        for j in range(len(segments)):
            if i == j:
                continue
            crossing = _wrap(2.0 * (segments[j, 1] - segments[i, 1])) / 2.0
            if abs(crossing) < settings.min_crossing:
                continue
            # map pairs (a, b) whose angle (mod pi) matches: turn from a, position from both
            a, b = np.meshgrid(usable, usable, indexing="ij")
            a, b = a.ravel(), b.ravel()
            between = _wrap(2.0 * (alpha[b] - alpha[a])) / 2.0
            ok = np.abs(_wrap(2.0 * (between - crossing)) / 2.0) <= settings.angle_tolerance
            a, b = a[ok], b[ok]
            for flip in (0.0, math.pi):
                theta = _wrap(alpha[a] - segments[i, 1] + flip)
                poses = _solve(segments[i], segments[j], theta, a, b, rho, alpha)
                good = _fits(segments[i], poses, a, lines, sides, settings)
                good &= _fits(segments[j], poses, b, lines, sides, settings)
                out.append(poses[good])
    return np.concatenate(out) if out else np.zeros((0, 3))


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
    """A pose hypothesis: a copy of the filter and the shares of returns it explained."""

    def __init__(self, tracker) -> None:
        self.tracker = tracker
        self.shares: list[float] = []

    @property
    def pose(self) -> Pose:
        return tuple(float(v) for v in self.tracker.state[:3])  # type: ignore[return-value]

    def recent(self, count: int) -> float:
        last = self.shares[-count:]
        return float(np.mean(last)) if last else 0.0


class GlobalSearch:
    """Hypotheses on the map of ``tracker`` (a :class:`~scanlines.map.filter.
    LineMapFilter`, whose lines and settings the hypotheses share)."""

    def __init__(self, tracker, settings: SearchSettings | None = None, extractor=None) -> None:
        from scanlines.extractor import Extractor

        self.settings = settings or SearchSettings()
        self.tracker = tracker
        self.extractor = extractor or Extractor()
        lines = tracker.lines
        self.grid = ExplainedGrid(lines.start, lines.end, self.settings.near, self.settings.cell)
        self.hypotheses: list[Hypothesis] = []

    def sample(self, points: np.ndarray) -> np.ndarray:
        """The returns scored (evenly subsampled)."""
        count = self.settings.score_points
        if len(points) <= count:
            return points
        return points[np.linspace(0, len(points) - 1, count).round().astype(np.intp)]

    def explained(self, points: np.ndarray, pose: Pose) -> float:
        """The share of the scan's returns within ``near`` of a map line at ``pose``."""
        return float(self.grid.shares(self.sample(points), np.asarray(pose))[0])

    def propose(self, scan, errors: np.ndarray | None, errors_cov: np.ndarray | None) -> int:
        """New hypotheses from ``scan``'s segments (``errors``: the odometry's errors and
        their covariance to start them with, state[3:] of the filter); how many."""
        s = self.settings
        extraction = self.extractor(scan)
        rows = np.asarray(extraction.lines)[:, :6]
        poses = pose_candidates(rows, self.tracker.lines, s)
        if not len(poses):
            return 0
        points = self.sample(scan.points[scan.valid].astype(np.float64))
        scores = self.grid.shares(points, poses)
        added = 0
        for k in _distinct(poses, scores, s, s.candidates):
            if scores[k] < s.drop_share:
                break
            if any(_same(poses[k], h.pose, s) for h in self.hypotheses):
                continue
            hypothesis = self._hypothesis(poses[k], errors, errors_cov)
            all_points = scan.points[scan.valid].astype(np.float64)
            hypothesis.tracker.step(all_points, None)  # aligned on the scan it came from
            hypothesis.shares.append(float(self.grid.shares(points, hypothesis.pose)[0]))
            self.hypotheses.append(hypothesis)
            added += 1
        self._trim()
        return added

    def _hypothesis(self, pose, errors, errors_cov) -> Hypothesis:
        s = self.settings
        tracker = copy.copy(self.tracker)
        tracker.start(tuple(float(v) for v in pose), (s.sigma_xy, s.sigma_theta))
        if errors is not None and errors_cov is not None:
            tracker.state[3:] = errors
            tracker.covariance[3:, 3:] = errors_cov
        return Hypothesis(tracker)

    def step(self, points: np.ndarray, increment: Pose | None) -> None:
        """Each hypothesis stepped on the scan (sensor-frame returns) and scored; the poor
        and the duplicates dropped."""
        s = self.settings
        sample = self.sample(points)
        for h in self.hypotheses:
            h.tracker.step(points, increment)
            h.shares.append(float(self.grid.shares(sample, np.asarray(h.pose))[0]))
        kept: list[Hypothesis] = []
        for h in sorted(self.hypotheses, key=lambda h: -len(h.shares)):
            if len(h.shares) >= 3 and h.recent(3) < s.drop_share:
                continue
            if any(_same(h.pose, k.pose, s) for k in kept):
                continue
            kept.append(h)
        self.hypotheses = kept

    def _trim(self) -> None:
        s = self.settings
        if len(self.hypotheses) > s.max_hypotheses:
            self.hypotheses.sort(key=lambda h: -h.recent(s.agree))
            del self.hypotheses[s.max_hypotheses :]

    def winner(self, rival: float = 0.0) -> Hypothesis | None:
        """The hypothesis the last ``agree`` scans agree on: it explained ``found_share``
        of the returns over them, and neither another distinct hypothesis nor ``rival``
        (the filter's own share over them) came within ``margin``."""
        s = self.settings
        ready = [h for h in self.hypotheses if len(h.shares) >= s.agree]
        if not ready:
            return None
        best = max(ready, key=lambda h: h.recent(s.agree))
        score = best.recent(s.agree)
        if score < s.found_share or score < rival + s.margin:
            return None
        for h in self.hypotheses:
            if h is not best and not _same(h.pose, best.pose, s):
                if h.recent(s.agree) > score - s.margin:
                    return None
        return best

    def clear(self) -> None:
        self.hypotheses = []
