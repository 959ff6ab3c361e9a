"""Publishing a log's scans as ``sensor_msgs/LaserScan`` at their recorded rate, or a fixed one,
and its odometry on ``/odom`` and ``/tf``, the laser's mounting on ``/tf_static``."""

from __future__ import annotations

import itertools
import math
import statistics
import time
from collections.abc import Iterable, Sequence

from scanlines.geometry.poses import Pose, compose, invert
from scanlines.ros2 import convert
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import (
    default_qos,
    latched_qos,
    participant,
    prepare,
    ros_topic,
    wait_for_match,
)
from scanlines.scan import Scan

__all__ = ["Player", "monotonic_stamps", "schedule", "steps_back"]

#: The longest pause between two scans of a log (a recording's gap is shortened to it).
MAX_PAUSE = 1.0
#: Seconds from finding a subscriber to the first scan: discovery is two-way, and the
#: subscriber takes a moment more to accept this writer (scans sent before are lost).
SETTLE = 0.5
#: Seconds at most to wait, after the last scan, for reliable subscribers to have them all.
DRAIN = 5.0


def schedule(previous: float | None, current: float | None, rate: float | None) -> float:
    """Seconds from one scan to the next: ``1 / rate``, else the timestamps' difference
    (at most :data:`MAX_PAUSE`; 0.1 s for scans without times or going back in time)."""
    if rate is not None:
        return 1.0 / rate
    if previous is None or current is None or current < previous:
        return 0.1
    return min(current - previous, MAX_PAUSE)


#: The interval between restamped scans when no two of the log's stamps step forward.
DEFAULT_INTERVAL = 0.1


def steps_back(times: Sequence[float | None]) -> tuple[int, float]:
    """How many times ``times`` step back (or stand still) from one scan to the next, and
    the largest step back (seconds; scans without a time left out)."""
    known = [t for t in times if t is not None]
    back = [a - b for a, b in itertools.pairwise(known) if b <= a]
    return len(back), max(back, default=0.0)


def monotonic_stamps(times: Sequence[float | None]) -> list[float]:
    """Stamps that only go forward: from the first time on, the log's interval where it is
    positive, the median positive interval where the log's time steps back, stands still or
    is missing."""
    intervals = [
        b - a if a is not None and b is not None else -1.0 for a, b in itertools.pairwise(times)
    ]
    positive = [d for d in intervals if d > 0]
    usual = statistics.median(positive) if positive else DEFAULT_INTERVAL
    first = next((t for t in times if t is not None), 0.0)
    stamps = [first] if times else []
    for d in intervals:
        stamps.append(stamps[-1] + (d if d > 0 else usual))
    return stamps


#: Depth of the ``/tf`` writer: tf2's broadcasters and listeners keep the last 100.
TF_DEPTH = 100


class Player:
    """A LaserScan publisher on ``topic`` (ROS 2's default QoS, so both best-effort and
    reliable subscribers receive it), and of each scan's odometry, when it has a pose:
    the pose of ``base_frame`` in ``odom_frame`` as ``nav_msgs/Odometry`` on ``odom_topic``
    and as the transform ``odom_frame -> base_frame`` on ``tf_topic``, stamped as the scan
    and sent just before it; the laser's mounting ``base_frame -> frame_id`` once on
    ``tf_static_topic`` (transient local), so that RViz shows the scans in ``odom_frame``.
    The scan's pose is the laser's: the base's is the scan's pose less the mounting."""

    def __init__(
        self,
        *,
        domain_id: int = 0,
        loopback: bool = False,
        topic: str = "/scan",
        frame_id: str = "laser",
        tf_topic: str = "/tf",
        odom_frame: str = "odom",
        odom_topic: str = "/odom",
        tf_static_topic: str = "/tf_static",
        base_frame: str = "base_link",
    ) -> None:
        from cyclonedds.pub import DataWriter
        from cyclonedds.topic import Topic

        prepare(msg.LaserScan, msg.TFMessage, msg.Odometry)
        dp = participant(domain_id, loopback=loopback)
        self._participant = dp
        self.frame_id = frame_id
        self.odom_frame = odom_frame
        self.base_frame = base_frame
        self.tf_topic = tf_topic
        self.odom_topic = odom_topic
        self.tf_static_topic = tf_static_topic
        self.writer = DataWriter(dp, Topic(dp, ros_topic(topic), msg.LaserScan), default_qos())
        tf = Topic(dp, ros_topic(tf_topic), msg.TFMessage)
        self.tf_writer = DataWriter(dp, tf, default_qos(TF_DEPTH))
        odom = Topic(dp, ros_topic(odom_topic), msg.Odometry)
        self.odom_writer = DataWriter(dp, odom, default_qos(TF_DEPTH))
        static = Topic(dp, ros_topic(tf_static_topic), msg.TFMessage)
        self.static_writer = DataWriter(dp, static, latched_qos())
        #: Odometry poses published so far (each on /odom and /tf).
        self.transforms = 0

    def wait_for_subscriber(self, timeout: float) -> bool:
        """Wait up to ``timeout`` seconds for a subscriber (then :data:`SETTLE` more);
        whether one is there."""
        found = wait_for_match(self.writer, timeout)
        if found:
            time.sleep(SETTLE)
        return found

    def play(
        self,
        scans: Iterable[Scan],
        *,
        rate: float | None = None,
        stamps: Sequence[float] | None = None,
        mounting: Pose | None = None,
    ) -> int:
        """Publish ``scans`` paced as recorded (or at ``rate`` Hz); ``stamps``: each scan's
        stamp instead of its timestamp (:func:`monotonic_stamps`); ``mounting``: the laser's
        pose on the base (none: the base is where the laser is). Returns the scans
        published."""
        published, previous, due = 0, None, 0.0
        mounted = (0.0, 0.0, 0.0) if mounting is None else mounting
        for k, scan in enumerate(scans):
            stamp = scan.timestamp if stamps is None else stamps[k]
            # paced from the first scan read: opening a log can take a while, and scans due
            # meanwhile would go out in a burst that a sensor-data subscriber drops
            if published == 0:
                due = time.monotonic()
            else:
                due += schedule(previous, stamp, rate)
            previous = stamp
            pause = due - time.monotonic()
            if pause > 0:
                time.sleep(pause)
            message = convert.laser_scan(scan, self.frame_id, scan_time=0.0)
            message.header.stamp = convert.stamp_of(stamp or 0.0)
            if scan.pose is not None:
                if self.transforms == 0:
                    self._mount(mounted, message.header.stamp)
                self._odometry(compose(scan.pose, invert(mounted)), message.header.stamp)
            self.writer.write(message)
            published += 1
        self.writer.wait_for_acks(int(DRAIN * 1e9))
        if self.transforms:
            self.tf_writer.wait_for_acks(int(DRAIN * 1e9))
            self.odom_writer.wait_for_acks(int(DRAIN * 1e9))
        return published

    def _mount(self, mounting: Pose, stamp: msg.Time) -> None:
        self.static_writer.write(convert.transform(mounting, stamp, self.base_frame, self.frame_id))

    def _odometry(self, pose: Pose, stamp: msg.Time) -> None:
        """The base's ``pose`` on ``/odom`` and ``/tf``."""
        x, y, theta = pose
        odometry = msg.Odometry(
            header=msg.Header(stamp=stamp, frame_id=self.odom_frame),
            child_frame_id=self.base_frame,
        )
        odometry.pose.pose = msg.Pose(
            position=msg.Point(x, y, 0.0),
            orientation=msg.Quaternion(0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2)),
        )
        self.odom_writer.write(odometry)
        self.tf_writer.write(convert.transform(pose, stamp, self.odom_frame, self.base_frame))
        self.transforms += 1
