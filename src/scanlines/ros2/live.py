"""The node's localisation over DDS: AMCL's topics and frames around a :class:`Localizer`.

Reads the odometry (``nav_msgs/Odometry`` on ``odom``, or ``odom -> base_link`` on
``/tf``), the mounting (``/tf_static``) and ``initialpose`` (RViz's "2D Pose Estimate");
publishes, per scan, ``amcl_pose`` (``geometry_msgs/PoseWithCovarianceStamped``) and
``map -> odom`` on ``/tf``; and once, transient local, the map as a ``nav_msgs/OccupancyGrid``
on ``map`` and as a ``MarkerArray`` of its lines.
"""

from __future__ import annotations

import math
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, TextIO

import numpy as np

from scanlines.map.filter import INITIAL_SIGMA
from scanlines.ros2 import convert
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import (
    default_qos,
    latched_qos,
    prepare,
    ros_topic,
    sensor_data_qos,
    take_serialized,
)
from scanlines.ros2.frames import pose_of, seconds_of, strip_frame
from scanlines.ros2.localizer import LivePose, Localizer
from scanlines.ros2.map_topics import map_markers, occupancy_grid

__all__ = ["LiveFrames", "LiveLocalisation", "LiveStats", "LiveTopics"]

#: Seconds of wall time a scan waits for the odometry to reach its stamp.
ODOMETRY_WAIT = 0.5
#: Seconds ``map -> odom`` is dated ahead of its scan (AMCL's ``transform_tolerance``).
TRANSFORM_TOLERANCE = 0.1
#: Samples taken off an input reader at once.
TAKE = 1000
MAX_LATENCIES = 100_000


@dataclass(frozen=True)
class LiveTopics:
    """The topics (resolved names), AMCL's and tf2's by default."""

    odom: str = "/odom"
    tf: str = "/tf"
    tf_static: str = "/tf_static"
    initialpose: str = "/initialpose"
    amcl_pose: str = "/amcl_pose"
    map: str = "/map"
    map_markers: str = "/scanlines/map_markers"


@dataclass(frozen=True)
class LiveFrames:
    """The frames, AMCL's by default; ``odometry``: ``"odom"`` (the topic) or ``"tf"``."""

    global_frame: str = "map"
    odom_frame: str = "odom"
    base_frame: str = "base_link"
    odometry: str = "odom"


@dataclass
class LiveStats:
    """Scans localised (and of them those the map did not fit), scans before any initial
    pose, scans the odometry did not cover, and the latency from taking each scan off the
    reader to its pose written, in seconds."""

    localised: int = 0
    not_fit: int = 0
    waiting: int = 0
    without_odometry: int = 0
    latencies: deque = field(default_factory=lambda: deque(maxlen=MAX_LATENCIES))

    def summary(self) -> str:
        text = f"{self.localised} scans localised ({self.not_fit} did not fit the map)"
        if self.waiting:
            text += f", {self.waiting} before an initial pose"
        if self.without_odometry:
            text += f", {self.without_odometry} without odometry at their stamp"
        if self.latencies:
            ms = np.asarray(self.latencies) * 1e3
            text += (
                f"; latency scan to pose: median {np.median(ms):.2f} ms, "
                f"p99 {np.percentile(ms, 99):.2f} ms"
            )
        return text


def _take(reader: Any, kind: type) -> list:
    """The samples on ``reader`` decoded as ``kind``; one that does not decode is dropped."""
    out = []
    for data, info in take_serialized(reader, TAKE):
        if info.valid_data:
            try:
                out.append(kind.deserialize(data))
            except Exception:  # a sample that is no such message: nothing to use
                continue
    return out


class LiveLocalisation:
    """AMCL's topics around ``localizer`` on participant ``dp`` (module docstring)."""

    def __init__(
        self,
        localizer: Localizer,
        dp: Any,
        *,
        topics: LiveTopics = LiveTopics(),
        frames: LiveFrames = LiveFrames(),
        log: TextIO = sys.stderr,
    ) -> None:
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        prepare(msg.Odometry, msg.TFMessage, msg.PoseWithCovarianceStamped, msg.OccupancyGrid)
        self.localizer, self.topics, self.frames, self.log = localizer, topics, frames, log
        self.stats = LiveStats()
        self._pending: deque = deque()

        def topic(name: str, kind: type) -> Any:
            return Topic(dp, ros_topic(name), kind)

        if frames.odometry == "tf":
            self._odometry = DataReader(dp, topic(topics.tf, msg.TFMessage), default_qos(TAKE))
        else:  # best effort matches a reliable /odom and a best-effort one (drivers send both)
            odom = topic(topics.odom, msg.Odometry)
            self._odometry = DataReader(dp, odom, sensor_data_qos(TAKE))
        self._static = DataReader(dp, topic(topics.tf_static, msg.TFMessage), latched_qos(100))
        self._initial = DataReader(dp, topic(topics.initialpose, msg.PoseWithCovarianceStamped),
                                   default_qos())  # fmt: skip
        self._tf = DataWriter(dp, topic(topics.tf, msg.TFMessage), default_qos(100))
        self._pose = DataWriter(dp, topic(topics.amcl_pose, msg.PoseWithCovarianceStamped),
                                default_qos())  # fmt: skip
        self._map = DataWriter(dp, topic(topics.map, msg.OccupancyGrid), latched_qos())
        self._markers = DataWriter(dp, topic(topics.map_markers, msg.MarkerArray), latched_qos())

    @property
    def readers(self) -> list:
        """The readers whose samples should wake the node."""
        return [self._odometry, self._static, self._initial]

    def publish_map(self) -> None:
        """The map on ``map`` and ``map_markers``, once (transient local: later
        subscribers get it too)."""
        filt, frame = self.localizer.filter, self.localizer.frame
        stamp = convert.stamp_of(time.time())
        name = self.frames.global_frame
        self._map.write(occupancy_grid(filt.lines, frame, name, stamp))
        self._markers.write(map_markers(filt.lines, frame, name, stamp))

    def poll(self) -> None:
        """Take what the input readers hold, then localise the scans whose odometry came."""
        self._read_odometry()
        for message in _take(self._static, msg.TFMessage):
            for t in message.transforms:
                pose = pose_of(t.transform.translation, t.transform.rotation)
                self.localizer.static.add(t.header.frame_id, t.child_frame_id, pose)
        for message in _take(self._initial, msg.PoseWithCovarianceStamped):
            self._set_initial(message)
        self._run_pending()

    def _read_odometry(self) -> None:
        buffer = self.localizer.odometry
        if self.frames.odometry != "tf":
            for odom in _take(self._odometry, msg.Odometry):
                pose = odom.pose.pose
                buffer.add(seconds_of(odom.header.stamp), pose_of(pose.position, pose.orientation))
            return
        parent, child = strip_frame(self.frames.odom_frame), strip_frame(self.frames.base_frame)
        for message in _take(self._odometry, msg.TFMessage):
            for t in message.transforms:
                if (
                    strip_frame(t.header.frame_id) == parent
                    and strip_frame(t.child_frame_id) == child
                ):
                    pose = pose_of(t.transform.translation, t.transform.rotation)
                    buffer.add(seconds_of(t.header.stamp), pose)

    def _set_initial(self, message: msg.PoseWithCovarianceStamped) -> None:
        frame_id = strip_frame(message.header.frame_id)
        if frame_id != strip_frame(self.frames.global_frame):
            self._say(
                f"ignored an initial pose in frame {frame_id!r} (not {self.frames.global_frame!r})"
            )
            return
        pose = pose_of(message.pose.pose.position, message.pose.pose.orientation)
        c = message.pose.covariance
        xy, yaw = max(c[0], c[7]), c[35]
        sigma = (math.sqrt(xy), math.sqrt(yaw)) if xy > 0 and yaw > 0 else INITIAL_SIGMA
        stamp = seconds_of(message.header.stamp)
        taken = self.localizer.set_initial(stamp, pose, sigma)
        when = (
            f"at stamp {stamp:.3f}"
            if taken == stamp
            else f"stamped {stamp:.3f}, ahead of the odometry (another clock): at the next scan"
        )
        self._say(
            f"initial pose x {pose[0]:.3f} m, y {pose[1]:.3f} m, yaw {math.degrees(pose[2]):.1f} "
            f"deg in {frame_id} {when} (sigma {sigma[0]:.3f} m, {math.degrees(sigma[1]):.2f} deg)"
        )

    def on_scan(self, scan: Any, header: msg.Header, received: float) -> None:
        """Queue one scan (taken off the reader at ``received``, ``perf_counter``) and
        localise what the odometry allows."""
        points = scan.points[scan.valid]
        self._pending.append((points, seconds_of(header.stamp), header, received))
        self._run_pending()

    @property
    def pending(self) -> int:
        return len(self._pending)

    def _run_pending(self) -> None:
        """Localise the queued scans in order; the first whose stamp the odometry has not
        reached waits (at most :data:`ODOMETRY_WAIT`), and those behind it."""
        now = time.perf_counter()
        while self._pending:
            points, stamp, header, received = self._pending[0]
            state = self.localizer.odometry_state(stamp)
            if state == "wait" and now - received < ODOMETRY_WAIT:
                return
            self._pending.popleft()
            if state != "ready":
                self.stats.without_odometry += 1
                continue
            if self.localizer.waiting_for_initial_pose:
                self.stats.waiting += 1
                continue
            live = self.localizer.localise(points, stamp, strip_frame(header.frame_id))
            if live is None:
                self.stats.waiting += 1
                continue
            self._publish(live, header.stamp)
            self.stats.latencies.append(time.perf_counter() - received)
            self.stats.localised += 1
            self.stats.not_fit += live.status != "aligned"

    def _publish(self, live: LivePose, stamp: msg.Time) -> None:
        frames = self.frames
        self._pose.write(amcl_pose(live, stamp, frames.global_frame))
        ahead = convert.stamp_of(seconds_of(stamp) + TRANSFORM_TOLERANCE)
        self._tf.write(
            convert.transform(live.map_to_odom, ahead, frames.global_frame, frames.odom_frame)
        )

    def drain(self, timeout: float) -> None:
        """Poll until no scan waits or ``timeout`` seconds passed (the node stopping)."""
        deadline = time.monotonic() + timeout
        while self._pending and time.monotonic() < deadline:
            time.sleep(0.01)
            self.poll()

    def _say(self, text: str) -> None:
        print(f"scanlines ros2: {text}", file=self.log, flush=True)


def amcl_pose(live: LivePose, stamp: msg.Time, frame_id: str) -> msg.PoseWithCovarianceStamped:
    """A localised scan as AMCL's ``amcl_pose``: the base's pose in ``frame_id`` with its
    covariance (x, y and yaw; z, roll and pitch zero)."""
    x, y, theta = live.base
    covariance = [0.0] * 36
    for i, a in enumerate((0, 1, 5)):
        for j, b in enumerate((0, 1, 5)):
            covariance[6 * a + b] = float(live.covariance[i, j])
    pose = msg.Pose(
        position=msg.Point(x, y, 0.0),
        orientation=msg.Quaternion(0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2)),
    )
    return msg.PoseWithCovarianceStamped(
        header=msg.Header(stamp=stamp, frame_id=frame_id),
        pose=msg.PoseWithCovariance(pose=pose, covariance=covariance),
    )
