"""Scan-to-scan registration: a short, robust point-to-line ICP (numpy only).

:func:`icp` refines the relative pose of two scans from an initial guess (the relative
pose of the log's poses, or the identity): the points of the *source* scan ``j`` are
moved into the frame of the *target* scan ``i`` and pulled onto the local lines of
``i``'s returns::

    from scanlines.geometry.registration import icp, line_target, relative_pose

    guess = relative_pose(scan_i.pose, scan_j.pose)      # j's frame in i's frame
    fit = icp(scan_j.points[scan_j.valid], line_target(scan_i), guess)
    fit.pose, fit.rms, fit.inlier_fraction

Conventions
-----------
A pose ``(x, y, theta)`` maps a point ``p`` of its frame to ``R(theta) p + (x, y)``.
The relative pose of scans ``i`` and ``j`` maps ``j``'s sensor frame into ``i``'s:
``inverse(pose_i) o pose_j`` (:func:`relative_pose`).

The method
----------
* Target lines: every valid return of ``i`` with a normal from a principal-component
  fit to itself and its neighbours (up to ``normal_window`` valid returns on each side
  in beam order, within ``neighbour_radius`` or three beam spacings times the window,
  whichever is larger); returns whose neighbourhood is not elongated (minor to major
  spread above ``max_flatness``) or has fewer than 3 points get no normal and are not
  used.
* Correspondence: the nearest target point (brute force over all target points; the
  source is subsampled evenly to at most ``max_points``), kept when it is within the
  gate. The gate starts at ``max_distance`` and shrinks by ``shrink`` each time an
  update moves less than 1 mm (and 1 mrad), down to ``min_distance`` (coarse to fine;
  the hard gate trims the far pairs).
* Update: Gauss-Newton on the point-to-line residuals ``n . (R p + t - q)`` with Huber
  weights (``huber`` metres), a small ridge so a direction the scene does not constrain
  (a corridor's axis) stays at the initial guess instead of drifting
  (:func:`point_to_line_step`, the step the map's alignment takes too).
* Stop when an update moves less than ``tolerance`` (metres and radians) at the final
  gate, or after ``max_iterations``.

Quality (:class:`Registration`): at the final gate, the inliers are the source points
whose point-to-line residual is within ``inlier_residual``; ``rms`` is the RMS of
their residuals and ``inlier_fraction`` their share of the (subsampled) source points.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np

from scanlines import _core
from scanlines.geometry.poses import IDENTITY, Pose, compose, invert, relative_pose
from scanlines.params import MAX_COUNT, MAX_METRES, Param, integer, number
from scanlines.params.tables import Groups, SettingsTable
from scanlines.scan import Scan

__all__ = [
    "IcpSettings",
    "LineStep",
    "LineTarget",
    "Pose",
    "Registration",
    "compose",
    "icp",
    "invert",
    "line_target",
    "point_to_line_step",
    "relative_pose",
    "transform_points",
]


def transform_points(points: np.ndarray, pose: Sequence[float]) -> np.ndarray:
    """``K x 2`` points moved by ``pose`` (``R p + t``)."""
    x, y, t = (float(v) for v in pose)
    c, s = math.cos(t), math.sin(t)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return np.column_stack((c * pts[:, 0] - s * pts[:, 1] + x, s * pts[:, 0] + c * pts[:, 1] + y))


class IcpSettings(SettingsTable):
    """The constants of :func:`icp` and :func:`line_target` (metres, radians)."""

    groups: ClassVar[Groups] = {
        "correspondence": {
            "max_distance": Param(
                0.5,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "the gate of a pair at the start: a source point's nearest target point (m)",
            ),
            "min_distance": Param(
                0.15,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "the final gate, where the gate stops shrinking; inliers lie within it (m)",
            ),
            "shrink": Param(
                0.6,
                number(low=0.0, low_open=True, high=1.0),
                "the gate's factor each time an update moves less than 1 mm (and 1 mrad)",
            ),
        },
        "fit": {
            "huber": Param(
                0.02,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "Huber width of the point-to-line residuals (m)",
            ),
            "inlier_residual": Param(
                0.05,
                number(low=0.0, high=MAX_METRES),
                "an inlier's point-to-line residual is at most this (m)",
            ),
            "max_iterations": Param(60, integer(1, MAX_COUNT), "most Gauss-Newton updates"),
            "max_points": Param(
                400, integer(3, MAX_COUNT), "source points used (evenly subsampled)"
            ),
            "tolerance": Param(
                1e-5,
                number(low=0.0),
                "an update smaller than this at the final gate ends the fit (m, rad)",
            ),
        },
        "target": {
            "normal_window": Param(
                3,
                integer(1, MAX_COUNT),
                "valid returns on each side fitted with a return for its line's normal",
            ),
            "neighbour_radius": Param(
                0.15,
                number(low=0.0, high=MAX_METRES),
                "those neighbours lie within this, or 3 beam spacings per window step (m)",
            ),
            "max_flatness": Param(
                0.3,
                number(low=0.0, high=1.0),
                "a neighbourhood's minor to major spread above this gives no normal",
            ),
        },
    }

    def check(self) -> None:
        self.require_at_most("min_distance", "max_distance")


class LineTarget(NamedTuple):
    """The target of a registration: points of a scan with the normal of their local line."""

    points: np.ndarray
    normals: np.ndarray


def line_target(scan: Scan, settings: IcpSettings | None = None) -> LineTarget:
    """The valid returns of ``scan`` that have a local line, with its unit normal."""
    settings = settings or IcpSettings()
    valid = np.flatnonzero(scan.valid)
    pts = scan.points[valid]
    n = len(pts)
    if n < 3:
        return LineTarget(np.zeros((0, 2)), np.zeros((0, 2)))
    radius = np.maximum(
        settings.neighbour_radius,
        3.0 * settings.normal_window * scan.ranges[valid] * abs(scan.angle_increment),
    )
    w = settings.normal_window
    sums = np.zeros((n, 2))
    count = np.zeros(n)
    members = []
    for offset in range(-w, w + 1):
        k = np.arange(n) + offset
        inside = (k >= 0) & (k < n)
        k = np.clip(k, 0, n - 1)
        near = inside & (np.hypot(*(pts[k] - pts).T) <= radius)
        members.append((k, near))
        sums += np.where(near[:, None], pts[k], 0.0)
        count += near
    mean = sums / count[:, None]
    sxx = np.zeros(n)
    syy = np.zeros(n)
    sxy = np.zeros(n)
    for k, near in members:
        d = np.where(near[:, None], pts[k] - mean, 0.0)
        sxx += d[:, 0] ** 2
        syy += d[:, 1] ** 2
        sxy += d[:, 0] * d[:, 1]
    # Eigenvalues and the minor eigenvector of the 2 x 2 scatter matrix, in closed form.
    half_trace = (sxx + syy) / 2.0
    root = np.sqrt(((sxx - syy) / 2.0) ** 2 + sxy**2)
    major, minor = half_trace + root, np.maximum(half_trace - root, 0.0)
    direction = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # the major axis
    normals = np.column_stack((-np.sin(direction), np.cos(direction)))
    with np.errstate(invalid="ignore", divide="ignore"):
        flat = np.sqrt(minor / major) <= settings.max_flatness
    keep = (count >= 3) & (major > 0.0) & flat
    return LineTarget(pts[keep], normals[keep])


@dataclass(frozen=True)
class Registration:
    """The result of :func:`icp`.

    Attributes
    ----------
    pose:
        Refined relative pose: maps the source scan's frame into the target's.
    initial:
        The initial guess it started from.
    rms:
        RMS point-to-line residual of the inliers, metres (NaN without inliers).
    inlier_fraction:
        Inliers over the source points used.
    n_inliers, n_source:
        Inliers and source points used.
    iterations:
        Gauss-Newton updates made.
    converged:
        Whether the last update was below the tolerance at the final gate.
    """

    pose: Pose
    initial: Pose
    rms: float
    inlier_fraction: float
    n_inliers: int
    n_source: int
    iterations: int
    converged: bool


_COARSE = 1e-3
"""An update smaller than this (metres, radians) shrinks the gate."""

_RIDGE = 1e-6
"""The ridge of :func:`icp`'s steps: this share of the normal matrix's mean diagonal."""


class LineSystem(NamedTuple):
    """The Huber-weighted normal equations of point-to-line residuals: the normal matrix
    ``J' W J``, the gradient ``J' W e`` and the weighted sum of squares ``e' W e``."""

    normal: np.ndarray
    gradient: np.ndarray
    weighted_sse: float


class LineStep(NamedTuple):
    """One Gauss-Newton step: the pose update ``(dx, dy, dtheta)`` and the normal matrix
    ``J' W J`` (before any ridge) it was solved with."""

    update: np.ndarray
    normal: np.ndarray


def point_to_line_system(
    lever: np.ndarray, normals: np.ndarray, residuals: np.ndarray, huber: float
) -> LineSystem:
    """The normal equations of a pose update that brings points onto their lines: the one
    linearisation of :func:`point_to_line_step` (scan to scan, scan to map) and of the map
    tracker's steps with a prior (:func:`scanlines.map.tracking.track_points`).

    A point ``p`` on a line of unit normal ``n`` has the residual ``e = n . p - rho``; a
    small update ``(dx, dy, dtheta)`` turning about a centre ``c`` changes it by
    ``n . (dx, dy) + dtheta (n_y l_x - n_x l_y)``, ``l = p - c`` (``lever``, K x 2). The
    weights are Huber's (``huber`` metres); a pair whose weighted residual is not finite is
    left out. One compiled routine (``cpp/scanlines/map/point_to_line.hpp``) linearises for
    this function and for the localisation filter's kernel, which weighs each pair over its
    residual's variance."""
    normal, gradient, weighted_sse = _core.point_to_line_system(
        np.asarray(lever, dtype=np.float64).reshape(-1, 2),
        np.asarray(normals, dtype=np.float64).reshape(-1, 2),
        np.asarray(residuals, dtype=np.float64).reshape(-1),
        float(huber),
    )
    return LineSystem(normal, gradient, weighted_sse)


def point_to_line_step(
    lever: np.ndarray,
    normals: np.ndarray,
    residuals: np.ndarray,
    huber: float,
    ridge: float | None = None,
) -> LineStep | None:
    """One Huber-weighted Gauss-Newton step on point-to-line residuals
    (:func:`point_to_line_system`): the pose update that brings points onto their lines,
    the one step of :func:`icp` (scan to scan) and of
    :func:`scanlines.map.align.align_points` (scan to map).

    With a ``ridge``, that share of the normal matrix's mean diagonal is added to it, so a
    direction the points do not constrain (a corridor's axis) stays where it is; without
    one, ``None`` where the normal matrix is not finite or its determinant not positive."""
    h, gradient, _ = point_to_line_system(lever, normals, residuals, huber)
    if ridge is None:
        if not np.all(np.isfinite(h)) or np.linalg.det(h) <= 0:
            return None
        solved = h
    else:
        solved = h + np.eye(3) * (ridge * np.trace(h) / 3.0 + 1e-12)
    return LineStep(-np.linalg.solve(solved, gradient), h)


def _subsample(points: np.ndarray, most: int) -> np.ndarray:
    if len(points) <= most:
        return points
    return points[np.linspace(0, len(points) - 1, most).round().astype(np.intp)]


def _nearest(points: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of and distance to the nearest target point of every point (brute force)."""
    d2 = (
        np.sum(points**2, axis=1)[:, None]
        + np.sum(target**2, axis=1)[None, :]
        - 2.0 * points @ target.T
    )
    index = np.argmin(d2, axis=1)
    return index, np.sqrt(np.maximum(d2[np.arange(len(points)), index], 0.0))


def icp(
    source: np.ndarray,
    target: LineTarget,
    initial: Sequence[float] = IDENTITY,
    settings: IcpSettings | None = None,
) -> Registration:
    """Refine the pose of ``source`` points (their own frame) onto ``target``'s lines.

    Parameters
    ----------
    source:
        ``K x 2`` points of the source scan in its sensor frame (valid returns only).
    target:
        :func:`line_target` of the target scan.
    initial:
        Initial guess of the relative pose (source frame in target frame).
    settings:
        :class:`IcpSettings`; the defaults when ``None``.

    Returns
    -------
    Registration
    """
    settings = settings or IcpSettings()
    initial = tuple(float(v) for v in initial)
    pose = initial
    src = _subsample(np.asarray(source, dtype=np.float64).reshape(-1, 2), settings.max_points)
    if len(src) < 3 or len(target.points) < 3:
        return Registration(pose, initial, math.nan, 0.0, 0, len(src), 0, False)
    gate = settings.max_distance
    iterations = 0
    converged = False
    while iterations < settings.max_iterations:
        moved = transform_points(src, pose)
        index, distance = _nearest(moved, target.points)
        ok = distance <= gate
        if np.count_nonzero(ok) < 3:
            break
        p, q, n = moved[ok], target.points[index[ok]], target.normals[index[ok]]
        e = np.sum(n * (p - q), axis=1)
        step = point_to_line_step(p, n, e, settings.huber, ridge=_RIDGE).update  # about the origin
        pose = compose((step[0], step[1], step[2]), pose)
        iterations += 1
        size = max(abs(step[0]), abs(step[1]), abs(step[2]))
        if gate <= settings.min_distance and size < settings.tolerance:
            converged = True
            break
        if size < _COARSE:
            gate = max(settings.min_distance, gate * settings.shrink)
    moved = transform_points(src, pose)
    index, distance = _nearest(moved, target.points)
    e = np.sum(target.normals[index] * (moved - target.points[index]), axis=1)
    inlier = (distance <= settings.min_distance) & (np.abs(e) <= settings.inlier_residual)
    n_in = int(np.count_nonzero(inlier))
    rms = float(np.sqrt(np.mean(e[inlier] ** 2))) if n_in else math.nan
    return Registration(pose, initial, rms, n_in / len(src), n_in, len(src), iterations, converged)
