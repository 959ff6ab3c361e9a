"""Pose candidates from a scan's segments on a map: two crossing walls, or a wall and its end."""

from __future__ import annotations

import math

import numpy as np

from scanlines.extraction import END_KINDS
from scanlines.map.search_settings import SearchSettings

__all__ = ["LineEnds", "LinePairs", "end_candidates", "pose_candidates"]


def _wrap(angle):
    return np.mod(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


def _longest(segments: np.ndarray, settings: SearchSettings) -> np.ndarray:
    """The rows of the longest of a scan's segments (rows: rho, alpha, start x, y, end
    x, y)."""
    length = np.hypot(segments[:, 4] - segments[:, 2], segments[:, 5] - segments[:, 3])
    keep = np.flatnonzero(length >= settings.min_segment)
    return keep[np.argsort(-length[keep])][: settings.segments]


def _segments(segments: np.ndarray, settings: SearchSettings) -> np.ndarray:
    """The longest of a scan's segments."""
    return segments[_longest(segments, settings)]


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


class LineEnds:
    """For each map line ``a`` at least ``min_line`` long: the end points of such lines
    (``b``, ``a`` itself among them) within ``max_pair_distance`` of it, each with its
    signed offset from ``a``'s line; sorted by that offset."""

    def __init__(self, lines, settings: SearchSettings) -> None:
        start, end = np.asarray(lines.start), np.asarray(lines.end)
        alpha, rho = np.asarray(lines.alpha), np.asarray(lines.rho)
        self.length = np.hypot(*(end - start).T)
        usable = np.flatnonzero(self.length >= settings.min_line)
        points = np.concatenate((start[usable], end[usable]))
        owners = np.concatenate((usable, usable))
        free = _open_ends(points, owners, start, end, settings.end_tolerance)
        lo, hi = np.minimum(start, end), np.maximum(start, end)
        a, offsets, at = [], [], []
        for line in usable:
            gap = np.maximum(0.0, np.maximum(lo[line] - points, points - hi[line]))
            near = np.flatnonzero(np.hypot(gap[:, 0], gap[:, 1]) <= settings.max_pair_distance)
            normal = np.array((math.cos(alpha[line]), math.sin(alpha[line])))
            offsets.append(points[near] @ normal - rho[line])
            a.append(np.full(len(near), line, dtype=np.intp))
            at.append(near)
        if not a:
            a, offsets, at = [np.zeros(0, np.intp)], [np.zeros(0)], [np.zeros(0, np.intp)]
        offset = np.concatenate(offsets)
        order = np.argsort(offset, kind="stable")
        self.a, self.offset = np.concatenate(a)[order], offset[order]
        at = np.concatenate(at)[order]
        self.b, self.point, self.open = owners[at], points[at], free[at]

    def matching(self, offset: float, tolerance: float, length: float):
        """The lines ``a`` at least ``length`` long, and the end points (of lines ``b``)
        ``offset`` from them within ``tolerance``."""
        lo = np.searchsorted(self.offset, offset - tolerance, side="left")
        hi = np.searchsorted(self.offset, offset + tolerance, side="right")
        k = np.arange(lo, hi)
        k = k[self.length[self.a[k]] >= length]
        return self.a[k], self.b[k], self.point[k], self.open[k]


def _open_ends(points, owners, start, end, tolerance: float) -> np.ndarray:
    """Whether each end point (of line ``owners``) lies farther than ``tolerance`` from
    every other map line: a wall's end (a doorway), not a corner or a break in a wall."""
    out = np.ones(len(points), dtype=bool)
    edge = end - start
    squared = np.maximum(np.sum(edge**2, axis=1), 1e-12)
    for block in range(0, len(points), 256):
        p = points[block : block + 256, None, :]  # P x 1 x 2
        t = np.clip(np.sum((p - start) * edge, axis=2) / squared, 0.0, 1.0)
        gap = np.hypot(*np.moveaxis(start + t[..., None] * edge - p, 2, 0))
        gap[np.arange(len(p)), owners[block : block + 256]] = np.inf
        out[block : block + 256] = gap.min(axis=1) > tolerance
    return out


def _real_ends(rows: np.ndarray, kinds: np.ndarray, settings: SearchSettings):
    """The ends of a scan's segments that are ends of a surface, as (segment row, x, y,
    open): a jump to a farther surface (open: a wall's end) or a corner."""
    jump, corner = END_KINDS.index("jump"), END_KINDS.index("corner")
    long = np.hypot(rows[:, 4] - rows[:, 2], rows[:, 5] - rows[:, 3]) >= settings.min_line
    out = []
    for j in np.flatnonzero(long):
        for side, column in ((0, 2), (1, 4)):
            if kinds[j, side] in (jump, corner):
                out.append((j, rows[j, column], rows[j, column + 1], kinds[j, side] == jump))
    return out


def end_candidates(rows: np.ndarray, kinds: np.ndarray, lines, ends: LineEnds,
                   settings: SearchSettings) -> np.ndarray:  # fmt: skip
    """Poses (H x 3) that put one of the scan's longest segments (``rows``: rho, alpha,
    start x, y, end x, y; ``kinds``: their :data:`~scanlines.extraction.END_KINDS` codes)
    on a map line, and a segment's real end (a corner or a jump) on the end point of a map
    line running as that segment does: the end fixes the position along the line, where
    two parallel walls fix none."""
    alpha = np.asarray(lines.alpha)
    sides = np.full(len(alpha), 3) if lines.sides is None else np.asarray(lines.sides)
    real = _real_ends(rows, kinds, settings)
    out = []
    for i in _longest(rows, settings):
        seg = rows[i]
        normal = np.array((math.cos(seg[1]), math.sin(seg[1])))
        need = _length(seg) - 2 * settings.overlap_slack
        for j, ex, ey, jump in real:
            offset = float(normal @ (ex, ey) - seg[0])
            for flip in (0.0, math.pi):
                a, b, point, free = ends.matching(
                    math.cos(flip) * offset, settings.end_tolerance, need
                )
                theta = _wrap(alpha[a] - seg[1] + flip)
                turn = np.abs(_half_turn(alpha[b] - rows[j, 1] - theta))
                keep = (turn <= settings.angle_tolerance) & (free == jump)
                a, b, point, theta = (v[keep] for v in (a, b, point, theta))
                c, s = np.cos(theta), np.sin(theta)
                poses = np.column_stack(
                    (point[:, 0] - c * ex + s * ey, point[:, 1] - s * ex - c * ey, theta)
                )
                good = _fits(seg, poses, a, lines, sides, settings)
                poses, b = poses[good], b[good]
                out.append(poses[_fits(rows[j], poses, b, lines, sides, settings)])
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
