"""How well a pose explains a scan on a line map: returns near its lines, beams cast on them."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ExplainedGrid", "beam_shares", "first_hits", "mapped"]


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
        reach = math.ceil(near / cell)
        di, dj = np.meshgrid(np.arange(-reach, reach + 1), np.arange(-reach, reach + 1))
        disk = np.hypot(di, dj) * cell <= near
        di, dj = di[disk], dj[disk]
        for a, b in zip(start, end, strict=True):
            count = max(2, math.ceil(np.hypot(*(b - a)) / (0.5 * cell)) + 1)
            t = np.linspace(0.0, 1.0, count)[:, None]
            cells = np.floor((a + t * (b - a) - self.origin) / cell).astype(np.int64)
            i = np.clip((cells[:, 0:1] + di).ravel(), 0, nx - 1)
            j = np.clip((cells[:, 1:2] + dj).ravel(), 0, ny - 1)
            self.bits[i, j] = True

    def _hits(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        i = np.floor((x - self.origin[0]) / self.cell).astype(np.int64)
        j = np.floor((y - self.origin[1]) / self.cell).astype(np.int64)
        nx, ny = self.bits.shape
        inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        hit = np.zeros(i.shape, dtype=bool)
        hit[inside] = self.bits[i[inside], j[inside]]
        return hit

    def crossed(self, points: np.ndarray, pose, clearance: float, reach: float) -> float:
        """The share of sensor-frame ``points`` whose beam, from the sensor at ``pose`` to
        ``clearance`` short of the return (at most ``reach`` metres), passes near a map
        line: a return seen through a wall, which a right pose does not have."""
        if not len(points):
            return 0.0
        r = np.hypot(points[:, 0], points[:, 1])
        t = np.arange(self.cell, reach, self.cell)  # distances along each beam
        along = t[None, :] <= (r - clearance)[:, None]  # K x T
        c, s = math.cos(pose[2]), math.sin(pose[2])
        ux, uy = points[:, 0] / np.maximum(r, 1e-9), points[:, 1] / np.maximum(r, 1e-9)
        wx = pose[0] + (c * ux - s * uy)[:, None] * t[None, :]
        wy = pose[1] + (s * ux + c * uy)[:, None] * t[None, :]
        return float(np.mean((self._hits(wx, wy) & along).any(axis=1)))

    def hits_at(self, points: np.ndarray, pose) -> np.ndarray:
        """Which of sensor-frame ``points`` are explained at ``pose``."""
        c, s = math.cos(pose[2]), math.sin(pose[2])
        x = pose[0] + c * points[:, 0] - s * points[:, 1]
        y = pose[1] + s * points[:, 0] + c * points[:, 1]
        return self._hits(x, y)

    def share_at(self, points: np.ndarray, pose) -> float:
        """:meth:`shares` at one ``pose`` in fewer array operations (each scan's lost test)."""
        if not len(points):
            return 0.0
        c, s = (float(f(np.full((1, 1), float(pose[2])))[0, 0]) for f in (np.cos, np.sin))
        x = pose[0] + c * points[:, 0] - s * points[:, 1]
        y = pose[1] + s * points[:, 0] + c * points[:, 1]
        return int(np.count_nonzero(self._hits(x, y))) / len(points)

    def shares(self, points: np.ndarray, poses: np.ndarray) -> np.ndarray:
        """The share of sensor-frame ``points`` (K x 2) explained at each of ``poses``
        (H x 3)."""
        poses = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
        if not len(points):
            return np.zeros(len(poses))
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        x = poses[:, 0:1] + c * points[:, 0] - s * points[:, 1]
        y = poses[:, 1:2] + s * points[:, 0] + c * points[:, 1]
        return self._hits(x, y).mean(axis=1)


def first_hits(points: np.ndarray, poses: np.ndarray, start: np.ndarray, end: np.ndarray,
               reach: float) -> np.ndarray:  # fmt: skip
    """The distance (H x K) along each beam, from the sensor at each of ``poses`` (H x 3)
    towards each sensor-frame return of ``points`` (K x 2), to the first map line (segments
    ``start`` to ``end``) it meets within ``reach``; ``inf`` where it meets none."""
    poses = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    out = np.full((len(poses), len(points)), np.inf)
    if not len(points) or not len(start):
        return out
    r = np.maximum(np.hypot(points[:, 0], points[:, 1]), 1e-9)
    ux, uy = points[:, 0] / r, points[:, 1] / r
    edge = end - start
    for h, (x, y, theta) in enumerate(poses):
        near = _lines_within(x, y, start, end, reach)
        if not len(near):
            continue
        c, s = np.cos(theta), np.sin(theta)
        dx, dy = (c * ux - s * uy)[:, None], (s * ux + c * uy)[:, None]  # K x 1
        ex, ey = edge[near, 0][None, :], edge[near, 1][None, :]  # 1 x L
        wx, wy = (start[near, 0] - x)[None, :], (start[near, 1] - y)[None, :]
        det = ex * dy - dx * ey  # of t d - u e = w
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (ex * wy - ey * wx) / det
            u = (dx * wy - dy * wx) / det
        t = np.where((np.abs(det) > 1e-12) & (u >= 0.0) & (u <= 1.0) & (t > 0.0), t, np.inf)
        out[h] = t.min(axis=1)
    out[out > reach] = np.inf
    return out


def _lines_within(x: float, y: float, start: np.ndarray, end: np.ndarray, reach: float):
    """The map lines whose box lies within ``reach`` of ``(x, y)``."""
    lo, hi = np.minimum(start, end), np.maximum(start, end)
    gap = np.maximum(0.0, np.maximum(lo - (x, y), (x, y) - hi))
    return np.flatnonzero(np.hypot(gap[:, 0], gap[:, 1]) <= reach)


def beam_shares(points: np.ndarray, pose, explained: np.ndarray, lines, clearance: float,
                reach: float) -> tuple[float, float]:  # fmt: skip
    """Of sensor-frame ``points`` at ``pose`` (``explained``: which lie near a map line), the
    shares not explained whose beam passes a map line of ``lines`` more than ``clearance``
    short of the return (seen through a wall) and whose beam ends more than ``clearance``
    short of the first map line on its way (something the map lacks in front of a wall). The
    rest meet no map line within ``reach``: a place the map lacks, which judges no pose."""
    if not len(points):
        return 0.0, 0.0
    hit = first_hits(points, np.asarray(pose, dtype=np.float64), lines.start, lines.end, reach)[0]
    r = np.hypot(points[:, 0], points[:, 1])
    unexplained = ~explained
    through = unexplained & (r > hit + clearance)
    short = unexplained & np.isfinite(hit) & (r < hit - clearance)
    return float(through.mean()), float(short.mean())


def mapped(shares: list[float], beams: list[tuple[float, float]], count: int, settings) -> bool:
    """Whether the last ``count`` scans of a hypothesis (its shares of returns explained and
    :func:`beam_shares`) explain the scans where the map has lines: at least
    ``mapped_share`` of all returns explained, at most ``max_through`` seen through a wall,
    and at least ``mapped_fraction`` of the returns whose beams meet a map line explained."""
    if len(beams) < count or len(shares) < count:
        return False
    explained = sum(shares[-count:]) / count
    through = sum(b[0] for b in beams[-count:]) / count
    short = sum(b[1] for b in beams[-count:]) / count
    judged = explained + through + short
    return (
        explained >= settings.mapped_share
        and through <= settings.max_through
        and explained >= settings.mapped_fraction * judged
    )
