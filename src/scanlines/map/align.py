"""Scan-to-map alignment: a scan's returns pulled onto the map's lines from the log's pose.

A few Gauss-Newton steps (:func:`~scanlines.geometry.registration.point_to_line_step`, the
step of the scan-to-scan ICP) on the point-to-line distances of the scan's valid returns (moved
into the world by the pose) to their nearest map line within a gate, Huber-weighted. The
correction is bounded (``align_max_shift``, ``align_max_turn``); when the scene does not
constrain every direction (one wall, a corridor of parallel walls: the smallest eigenvalue
of the normal equations too small) or too few returns meet a line, the log's pose stands.
"""

from __future__ import annotations

import math
from typing import ClassVar, NamedTuple

import numpy as np

from scanlines.geometry.poses import Pose
from scanlines.geometry.registration import point_to_line_step
from scanlines.geometry.transform import points_to_world
from scanlines.params import MAX_COUNT, MAX_METRES, MAX_SCANS, Param, integer, number
from scanlines.params.tables import Groups, SettingsTable

__all__ = [
    "AlignSettings",
    "Alignment",
    "LineSet",
    "align_points",
    "align_scan",
    "nearest_segments",
]

#: Returns used for an alignment (evenly subsampled).
MAX_POINTS = 400
#: Returns on a line needed before an alignment is trusted.
MIN_PAIRS = 20
#: The Huber width of the point-to-line residuals (metres).
HUBER = 0.02
#: The lever (metres) that weighs a turn against a shift in the constraint check.
LEVER = 1.0


class AlignSettings(SettingsTable):
    """The constants of scan-to-map alignment (metres, radians): the bounds of a correction,
    the gate of a return's line, the least constraint per direction, the scans a map line
    needs to be aligned to (``support``), the share of the correction applied (``damping``)."""

    groups: ClassVar[Groups] = {
        "alignment": {
            "max_shift": Param(
                0.1,
                number(low=0.0, high=MAX_METRES),
                "a larger correction is refused: the log's pose stands (m)",
            ),
            "max_turn": Param(
                math.radians(2.0),
                number(low=0.0, high=math.pi),
                "a larger turn is refused: the log's pose stands (rad)",
            ),
            "gate": Param(
                0.1,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "a return pairs with the nearest map line within this distance (m)",
            ),
            "least": Param(
                0.02,
                number(low=0.0),
                "least constraint of every direction: the normal matrix's smallest "
                "eigenvalue per pair (turns at a 1 m lever)",
            ),
        },
        "solver": {
            "iterations": Param(6, integer(1, MAX_COUNT), "most Gauss-Newton steps per scan"),
        },
        "map": {
            "support": Param(
                3,
                integer(1, MAX_SCANS),
                "a map line is aligned to once seen by this many scans",
            ),
        },
        "correction": {
            "damping": Param(
                1.0,
                number(low=0.0, low_open=True, high=1.0),
                "share of the correction applied to the log's pose",
            ),
        },
    }


class LineSet(NamedTuple):
    """Map lines as arrays: ``rho, alpha`` (L), ``start, end`` (L x 2), and the sides each
    was seen from (L; :data:`~scanlines.map.fusion.FRONT`, ``BACK`` or ``BOTH``; ``None``:
    both)."""

    rho: np.ndarray
    alpha: np.ndarray
    start: np.ndarray
    end: np.ndarray
    sides: np.ndarray | None = None


class Alignment(NamedTuple):
    """The aligned pose, and whether the alignment was used (else the pose given)."""

    pose: Pose
    used: bool
    pairs: int


def _subsample(points: np.ndarray) -> np.ndarray:
    if len(points) <= MAX_POINTS:
        return points
    return points[np.linspace(0, len(points) - 1, MAX_POINTS).round().astype(np.intp)]


def _near(lines: LineSet, world: np.ndarray, margin: float) -> LineSet:
    """The lines whose extent comes within ``margin`` of the points' bounding box."""
    lo, hi = world.min(axis=0) - margin, world.max(axis=0) + margin
    box_lo = np.minimum(lines.start, lines.end)
    box_hi = np.maximum(lines.start, lines.end)
    keep = np.all((box_lo <= hi) & (box_hi >= lo), axis=1)
    return LineSet(*(None if array is None else array[keep] for array in lines))


def nearest_segments(
    points: np.ndarray, start: np.ndarray, end: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """For each ``K x 2`` point: its distance to the nearest of the segments ``start[l]`` to
    ``end[l]`` and that segment's index (inf and -1 without segments)."""
    distance = np.full(len(points), np.inf)
    nearest = np.full(len(points), -1, dtype=np.intp)
    if not len(start):
        return distance, nearest
    ab = end - start
    length2 = np.maximum(np.sum(ab**2, axis=1), 1e-18)
    # A return kilometres away squares past the floats' range: its distance is inf.
    with np.errstate(over="ignore", invalid="ignore"):
        for lo in range(0, len(points), 256):  # bounded K x L blocks
            ap = points[lo : lo + 256, None, :] - start[None, :, :]
            t = np.clip(np.einsum("klj,lj->kl", ap, ab) / length2[None, :], 0.0, 1.0)
            d2 = np.sum((ap - t[:, :, None] * ab[None, :, :]) ** 2, axis=2)
            d2 = np.where(np.isnan(d2), np.inf, d2)
            nearest[lo : lo + 256] = np.argmin(d2, axis=1)
            distance[lo : lo + 256] = np.sqrt(np.min(d2, axis=1))
    return distance, nearest


def _pairs(world: np.ndarray, lines: LineSet, gate: float):
    """For each point within ``gate`` of a line segment: its index and the nearest line's."""
    distance, line = nearest_segments(world, lines.start, lines.end)
    ok = distance <= gate
    return np.flatnonzero(ok), line[ok]


def _step(world: np.ndarray, pose: Pose, lines: LineSet, gate: float):
    """One Gauss-Newton step ``(update, normal matrix, pairs)``, or None without pairs."""
    point, line = _pairs(world, lines, gate)
    if len(point) < MIN_PAIRS:
        return None
    p = world[point]
    n = np.column_stack((np.cos(lines.alpha[line]), np.sin(lines.alpha[line])))
    e = np.sum(n * p, axis=1) - lines.rho[line]
    found = point_to_line_step(p - np.array(pose[:2]), n, e, HUBER)  # about the sensor
    return None if found is None else (found.update, found.normal, len(point))


def _constrained(h: np.ndarray, pairs: int, least: float) -> bool:
    """Whether every direction of ``(x, y, theta * LEVER)`` is pinned by the returns: the
    smallest eigenvalue of the normal matrix per pair at least ``least``."""
    scale = np.diag([1.0, 1.0, 1.0 / LEVER])
    return float(np.linalg.eigvalsh(scale @ h @ scale)[0]) / pairs >= least


def align_points(
    points: np.ndarray,
    pose: Pose,
    lines: LineSet,
    *,
    max_shift: float,
    max_turn: float,
    gate: float,
    least: float,
    iterations: int = 6,
) -> Alignment:
    """Align sensor-frame ``points`` (K x 2) onto ``lines`` starting from ``pose``."""
    src = _subsample(np.asarray(points, dtype=np.float64).reshape(-1, 2))
    start = tuple(float(v) for v in pose)
    if len(src) < MIN_PAIRS or not len(lines.rho):
        return Alignment(start, False, 0)  # type: ignore[arg-type]
    lines = _near(lines, points_to_world(src, start), gate + max_shift)
    if not len(lines.rho):
        return Alignment(start, False, 0)  # type: ignore[arg-type]
    current, found = start, None
    for _ in range(iterations):
        found = _step(points_to_world(src, current), current, lines, gate)
        if found is None:
            return Alignment(start, False, 0)  # type: ignore[arg-type]
        update = found[0]
        current = (current[0] + update[0], current[1] + update[1], current[2] + update[2])
        if max(abs(update[0]), abs(update[1]), abs(update[2])) < 1e-5:
            break
    _, h, pairs = found  # type: ignore[misc]
    shift = math.hypot(current[0] - start[0], current[1] - start[1])
    turn = abs(math.remainder(current[2] - start[2], 2 * math.pi))
    if shift > max_shift or turn > max_turn or not _constrained(h, pairs, least):
        return Alignment(start, False, pairs)  # type: ignore[arg-type]
    wrapped = (current[0], current[1], math.remainder(current[2], 2 * math.pi))
    return Alignment(wrapped, True, pairs)


def align_scan(scan, pose: Pose, lines: LineSet, settings: AlignSettings) -> Alignment:
    """:func:`align_points` of a scan's valid returns."""
    fit = align_points(
        scan.points[scan.valid], pose, lines, max_shift=settings.max_shift,
        max_turn=settings.max_turn, gate=settings.gate, least=settings.least,
        iterations=settings.iterations,
    )  # fmt: skip
    if not fit.used or settings.damping == 1.0:
        return fit
    w = settings.damping
    turn = math.remainder(fit.pose[2] - pose[2], 2 * math.pi)
    damped = (pose[0] + w * (fit.pose[0] - pose[0]), pose[1] + w * (fit.pose[1] - pose[1]),
              math.remainder(pose[2] + w * turn, 2 * math.pi))  # fmt: skip
    return Alignment(damped, True, fit.pairs)
