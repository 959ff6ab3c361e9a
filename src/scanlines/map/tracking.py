"""Tracking on a line map: odometry as the prior, each scan aligned to the map's lines.

Each scan's pose is predicted by composing the odometry increment since the last tracked
scan (from the pose source: a raw log's odometry, a trajectory file, scan registration) onto
the last *corrected* pose, so odometry drift does not accumulate; the scan's returns are
then pulled onto the map's lines by Gauss-Newton on the point-to-line distances (Huber
weighted) *together with* the prior (the increment's noise, :class:`TrackSettings`): where
the scene pins no direction (a corridor), the prior holds it instead of the fit failing.

The fit's covariance is ``inverse(J' W J / s^2 + prior information)``, ``s^2`` the weighted
residuals' variance. A scan is *not aligned* (its predicted pose stands, and the caller
keeps it out of the map) when too few of its returns lie near a map line at the end
(``min_share``), or the correction from the prediction exceeds ``max_shift`` /
``max_turn``; ``reason`` says which.

``scanlines map --align`` and ``scanlines eval map --align`` track with this, not with the
filter of ``scanlines localize`` (:mod:`scanlines.map.filter`): on the raw Intel scans the
filter on the map being built gave an ATE of 0.725 m (0.47 to 1.28 m by its settings),
this 0.226 m (docs/MEASUREMENTS.md, "One tracker"). :func:`tracking_summary` and
:func:`write_tracked` live in :mod:`scanlines.map.tracked`, shared with ``localize``.
"""

from __future__ import annotations

import math
from typing import ClassVar, NamedTuple

import numpy as np

from scanlines.geometry.poses import Pose, compose, relative_pose
from scanlines.geometry.registration import point_to_line_system
from scanlines.geometry.transform import points_to_world
from scanlines.map.align import HUBER, MIN_PAIRS, LineSet, _near, _subsample, nearest_segments
from scanlines.map.tracked import tracking_summary, write_tracked
from scanlines.params import MAX_COUNT, MAX_METRES, MAX_SCANS, Param, integer, number
from scanlines.params.tables import Groups, SettingsTable

__all__ = [
    "OdometryTracker",
    "TrackFit",
    "TrackSettings",
    "track_points",
    "tracking_summary",
    "write_tracked",
]


class TrackSettings(SettingsTable):
    """The constants of tracking (metres, radians): the association gate, the largest
    correction of a prediction, the share of returns that must meet a line, the odometry
    increment's noise (a floor plus a share of the distance and the turn), the residual
    variance's floor, the Gauss-Newton steps and the step (metres, radians) at which they
    stop, the scans a map line needs before it is aligned to (``support``)."""

    groups: ClassVar[Groups] = {
        "alignment": {
            "gate": Param(
                0.15,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "a return meets a map line within this distance (m)",
            ),
            "max_shift": Param(
                0.3,
                number(low=0.0, high=MAX_METRES),
                "a larger correction of the prediction is refused (m)",
            ),
            "max_turn": Param(
                math.radians(10.0),
                number(low=0.0, high=math.pi),
                "a larger turn of the prediction is refused (rad)",
            ),
            "min_share": Param(
                0.3,
                number(low=0.0, high=1.0),
                "share of the scan's returns that must meet a map line",
            ),
        },
        "prior": {
            "odometry_floor": Param(
                0.01,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "an increment's position sigma when standing still (m)",
            ),
            "odometry_turn_floor": Param(
                math.radians(0.5),
                number(low=0.0, low_open=True, high=math.pi),
                "an increment's heading sigma when standing still (rad)",
            ),
            "odometry_per_metre": Param(
                0.1,
                number(low=0.0),
                "position sigma added per metre driven (m/m)",
            ),
            "odometry_per_radian": Param(
                0.1,
                number(low=0.0),
                "heading sigma added per radian turned, and a tenth of it per metre driven",
            ),
        },
        "solver": {
            "sigma_floor": Param(
                0.005,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "floor of the residuals' sigma that weighs the returns against the prior (m)",
            ),
            "iterations": Param(10, integer(1, MAX_COUNT), "most Gauss-Newton steps per scan"),
            "tolerance": Param(
                1e-6, number(low=0.0), "a smaller step (m, rad) ends the Gauss-Newton steps"
            ),
        },
        "map": {
            "support": Param(
                3,
                integer(1, MAX_SCANS),
                "a map line is aligned to once seen by this many scans",
            ),
        },
    }

    def increment_covariance(self, increment: Pose) -> np.ndarray:
        """The prior covariance (x, y, theta) of an odometry ``increment``."""
        distance = math.hypot(increment[0], increment[1])
        turn = abs(increment[2])
        xy = self.odometry_floor + self.odometry_per_metre * distance
        theta = self.odometry_turn_floor + self.odometry_per_radian * turn
        theta += self.odometry_per_radian * distance * 0.1  # a drive turns the heading too
        return np.diag([xy**2, xy**2, theta**2])


class TrackFit(NamedTuple):
    """The tracked pose, whether it was aligned (else the prediction), the returns that met
    a line, the pose's covariance (3 x 3, x y theta), and why not aligned (else None)."""

    pose: Pose
    used: bool
    pairs: int
    covariance: np.ndarray
    reason: str | None = None


def _wrap(angle: float) -> float:
    return float(math.remainder(angle, 2.0 * math.pi))


def track_points(
    points: np.ndarray,
    predicted: Pose,
    prior: np.ndarray,
    lines: LineSet,
    settings: TrackSettings,
) -> TrackFit:
    """Align sensor-frame ``points`` (K x 2) onto ``lines`` from ``predicted``, with the
    prior covariance ``prior`` (3 x 3) about it."""
    src = _subsample(np.asarray(points, dtype=np.float64).reshape(-1, 2))
    start = tuple(float(v) for v in predicted)

    def refuse(reason: str, pairs: int = 0) -> TrackFit:
        return TrackFit(start, False, pairs, prior, reason)  # type: ignore[arg-type]

    if len(src) < MIN_PAIRS:
        return refuse("too few returns")
    if not len(lines.rho):
        return refuse("no map lines")
    lines = _near(lines, points_to_world(src, start), settings.gate + settings.max_shift)
    if not len(lines.rho):
        return refuse("no map line near the scan")
    info_prior = np.linalg.inv(prior)
    normals = np.column_stack((np.cos(lines.alpha), np.sin(lines.alpha)))
    x = np.array(start)
    data = np.zeros((3, 3))
    pairs, residual = 0, 0.0
    for _ in range(settings.iterations):
        world = points_to_world(src, x)
        distance, nearest = nearest_segments(world, lines.start, lines.end)
        ok = distance <= settings.gate
        pairs = int(np.count_nonzero(ok))
        if pairs < MIN_PAIRS:
            return refuse("too few returns near a map line", pairs)
        p, n = world[ok], normals[nearest[ok]]
        e = np.sum(n * p, axis=1) - lines.rho[nearest[ok]]
        system = point_to_line_system(p - x[:2], n, e, HUBER)
        residual = system.weighted_sse / max(pairs - 3, 1)
        s2 = max(residual, settings.sigma_floor**2)
        data = system.normal / s2
        offset = x - np.array(start)
        offset[2] = _wrap(offset[2])
        gradient = system.gradient / s2 + info_prior @ offset
        step = -np.linalg.solve(data + info_prior, gradient)
        x = x + step
        if np.abs(step).max() < settings.tolerance:
            break
    covariance = np.linalg.inv(data + info_prior)
    shift = math.hypot(x[0] - start[0], x[1] - start[1])
    turn = abs(_wrap(x[2] - start[2]))
    if pairs < settings.min_share * len(src):
        return refuse(f"{pairs} of {len(src)} returns near a map line", pairs)
    if shift > settings.max_shift or turn > settings.max_turn:
        return refuse(f"a correction of {shift:.2f} m, {math.degrees(turn):.1f} deg", pairs)
    pose = (float(x[0]), float(x[1]), _wrap(float(x[2])))
    return TrackFit(pose, True, pairs, covariance)


class OdometryTracker:
    """Poses of successive scans: each odometry increment composed onto the last tracked
    pose (:meth:`predict`), the fit's (or the prediction's) pose kept (:meth:`advance`)."""

    def __init__(self, settings: TrackSettings) -> None:
        self.settings = settings
        self._odometry: Pose | None = None
        self._pose: Pose | None = None

    def predict(self, odometry: Pose) -> tuple[Pose, np.ndarray]:
        """The predicted pose of a scan whose odometry (or given) pose is ``odometry``, and
        the prior covariance of the increment; the first scan is where its odometry says."""
        if self._odometry is None or self._pose is None:
            return odometry, self.settings.increment_covariance((0.0, 0.0, 0.0))
        increment = relative_pose(self._odometry, odometry)
        return compose(self._pose, increment), self.settings.increment_covariance(increment)

    def advance(self, odometry: Pose, pose: Pose) -> None:
        """The scan at ``odometry`` was tracked to ``pose``."""
        self._odometry, self._pose = odometry, pose

    def start(self, odometry: Pose, pose: Pose) -> None:
        """Start (or restart) tracking: the scan at ``odometry`` stands at ``pose``."""
        self.advance(odometry, pose)
