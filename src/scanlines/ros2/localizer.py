"""Live localisation on a line map: ``localize``'s filter fed by stamped odometry, as AMCL is.

::

    localizer = Localizer(lines, frame)              # a map read by read_line_map
    localizer.odometry.add(t, (x, y, yaw))           # base_link in odom, as /odom or /tf tell
    localizer.static.add("base_link", "laser", m)    # the laser's mounting (/tf_static)
    localizer.set_initial(t0, (x0, y0, yaw0))        # base_link in map (/initialpose)
    pose = localizer.localise(points, t, "laser")    # each scan: returns, stamp, frame

Each scan's odometry is the base's pose interpolated at the scan's stamp, carried to the
laser by the mounting (``/tf_static``'s ``base_link -> laser``); without a mounting the
base's odometry stands for the laser's and the filter's learnt lever for the mounting. The
filter (:class:`~scanlines.map.filter.LineMapFilter`) then steps as ``scanlines localize``
steps, on the same increments, so a log played into the node gives ``localize``'s poses. An
initial pose applies at the first scan stamped at or after it, carried by the odometry from
its stamp to the scan's (a stamp of zero: the next scan; one more than a second ahead of the
newest odometry is another clock's, RViz's wall clock while a log plays: the next scan too).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from scanlines.geometry.poses import Pose, compose, invert, relative_pose
from scanlines.map.align import LineSet
from scanlines.map.filter import INITIAL_SIGMA, FilterSettings, LineMapFilter
from scanlines.map.frame import LocalFrame
from scanlines.ros2.frames import OdometryBuffer, StaticFrames

__all__ = ["LivePose", "Localizer"]

#: Seconds by which a scan may come before the initial pose's stamp and still take it
#: (a stamp's nanoseconds rounded).
STAMP_SLACK = 1e-6
#: Seconds an initial pose may be stamped ahead of the newest odometry before its stamp is
#: taken for another clock's (RViz's wall clock against a played log's).
OTHER_CLOCK = 1.0


class LivePose(NamedTuple):
    """One scan localised: its stamp, the base's pose in the map (world frame) with its
    3 x 3 covariance (x, y, yaw), the ``map -> odom`` transform, the laser's pose in the
    map, and the filter's status."""

    stamp: float
    base: Pose
    covariance: np.ndarray
    map_to_odom: Pose
    laser: Pose
    status: str


class Localizer:
    """The filter on one map with the odometry and frames it needs (module docstring):
    ``base_frame`` is the frame of the odometry's poses."""

    def __init__(
        self,
        lines: LineSet,
        frame: LocalFrame,
        *,
        base_frame: str = "base_link",
        settings: FilterSettings | None = None,
    ) -> None:
        self.frame = frame
        self.base_frame = base_frame
        self.filter = LineMapFilter(lines, settings)
        self.odometry = OdometryBuffer()
        self.static = StaticFrames()
        self._initial: tuple[float, Pose, tuple[float, float]] | None = None
        self._last: Pose | None = None  # the laser's odometry at the last scan

    @property
    def started(self) -> bool:
        return self._last is not None

    @property
    def waiting_for_initial_pose(self) -> bool:
        return self._initial is None and self._last is None

    def set_initial(
        self, stamp: float, pose: Pose, sigma: tuple[float, float] = INITIAL_SIGMA
    ) -> float:
        """Where the base stands in the map (world frame) at ``stamp`` (0: the next scan),
        with standard deviations ``sigma`` (metres, radians). Returns the stamp taken: 0
        for one from another clock (module docstring)."""
        newest = self.odometry.newest
        if newest is not None and stamp > newest + OTHER_CLOCK:
            stamp = 0.0
        self._initial = (stamp, tuple(float(v) for v in pose), sigma)
        return stamp

    def mounting(self, laser_frame: str) -> Pose | None:
        """The laser's pose on the base from the static transforms, if they hold it."""
        return self.static.lookup(self.base_frame, laser_frame)

    def odometry_state(self, stamp: float) -> str:
        """``"ready"`` when the odometry covers ``stamp``, ``"wait"`` when it has not yet
        reached it, ``"gone"`` when it starts after it."""
        newest = self.odometry.newest
        if newest is None or newest < stamp:
            return "wait"
        return "ready" if self.odometry.at(stamp) is not None else "gone"

    def localise(self, points: np.ndarray, stamp: float, laser_frame: str) -> LivePose | None:
        """One scan (its valid returns in the laser's frame, K x 2): ``None`` while no
        initial pose was given, or when the odometry does not cover ``stamp``."""
        odometry = self.odometry.at(stamp)
        if odometry is None:
            return None
        mounting = self.mounting(laser_frame)
        laser_odometry = odometry if mounting is None else compose(odometry, mounting)
        increment = None
        if self._initial is not None and stamp >= self._initial[0] - STAMP_SLACK:
            self._restart(odometry, mounting)
        elif self._last is None:
            return None
        else:
            increment = relative_pose(self._last, laser_odometry)
        step = self.filter.step(points, increment)
        self._last = laser_odometry
        laser = self.frame.world_pose(step.pose)
        lever = (float(step.state[5]), float(step.state[6]), 0.0)
        to_base = invert(lever if mounting is None else mounting)
        base = compose(laser, to_base)
        covariance = _carried(step.covariance, laser[2], to_base)
        return LivePose(stamp, base, covariance, compose(base, invert(odometry)), laser,
                        step.status)  # fmt: skip

    def _restart(self, odometry: Pose, mounting: Pose | None) -> None:
        """Start the filter at the pending initial pose, carried to this scan by the
        odometry when it covers the initial pose's stamp."""
        assert self._initial is not None
        stamp, base, sigma = self._initial
        self._initial = None
        then = self.odometry.at(stamp) if stamp > 0 else None
        if then is not None:
            base = compose(base, relative_pose(then, odometry))
        laser = base if mounting is None else compose(base, mounting)
        self.filter.start(self.frame.pose(laser), sigma)


def _carried(covariance: np.ndarray, heading: float, offset: Pose) -> np.ndarray:
    """The 3 x 3 covariance of the laser's pose (heading ``heading``) carried to the pose
    ``offset`` from it (first order)."""
    c, s = math.cos(heading), math.sin(heading)
    rx, ry = c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]
    jacobian = np.array([[1.0, 0.0, -ry], [0.0, 1.0, rx], [0.0, 0.0, 1.0]])
    return jacobian @ np.asarray(covariance, dtype=np.float64) @ jacobian.T
