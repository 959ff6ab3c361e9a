"""How well a pose hypothesis explains a scan where the map has lines: beams cast on the map."""

from __future__ import annotations

import numpy as np

__all__ = ["first_hits"]


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
