"""Publishing a log's scans as ``sensor_msgs/LaserScan`` at their recorded rate, or a fixed one,
and their poses on ``/tf``."""

from __future__ import annotations

import time
from collections.abc import Iterable

from scanlines.ros2 import convert
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import default_qos, participant, prepare, ros_topic, wait_for_match
from scanlines.scan import Scan

__all__ = ["Player", "schedule"]

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


#: Depth of the ``/tf`` writer: tf2's broadcasters and listeners keep the last 100.
TF_DEPTH = 100


class Player:
    """A LaserScan publisher on ``topic`` (ROS 2's default QoS, so both best-effort and
    reliable subscribers receive it), and of each scan's pose, when it has one, as the
    transform ``odom_frame -> frame_id`` on ``tf_topic`` (``tf2_msgs/TFMessage``, stamped as
    the scan and sent just before it, so that RViz can show the scans in ``odom_frame``)."""

    def __init__(
        self,
        *,
        domain_id: int = 0,
        loopback: bool = False,
        topic: str = "/scan",
        frame_id: str = "laser",
        tf_topic: str = "/tf",
        odom_frame: str = "odom",
    ) -> None:
        from cyclonedds.pub import DataWriter
        from cyclonedds.topic import Topic

        prepare(msg.LaserScan, msg.TFMessage)
        dp = participant(domain_id, loopback=loopback)
        self._participant = dp
        self.frame_id = frame_id
        self.odom_frame = odom_frame
        self.tf_topic = tf_topic
        self.writer = DataWriter(dp, Topic(dp, ros_topic(topic), msg.LaserScan), default_qos())
        tf = Topic(dp, ros_topic(tf_topic), msg.TFMessage)
        self.tf_writer = DataWriter(dp, tf, default_qos(TF_DEPTH))
        #: Transforms published so far.
        self.transforms = 0

    def wait_for_subscriber(self, timeout: float) -> bool:
        """Wait up to ``timeout`` seconds for a subscriber (then :data:`SETTLE` more);
        whether one is there."""
        found = wait_for_match(self.writer, timeout)
        if found:
            time.sleep(SETTLE)
        return found

    def play(
        self, scans: Iterable[Scan], *, rate: float | None = None, restamp: bool = False
    ) -> int:
        """Publish ``scans`` paced as recorded (or at ``rate`` Hz); ``restamp``: stamped
        with the time of sending instead of the log's. Returns the scans published."""
        published, previous, due = 0, None, 0.0
        for scan in scans:
            # paced from the first scan read: opening a log can take a while, and scans due
            # meanwhile would go out in a burst that a sensor-data subscriber drops
            if published == 0:
                due = time.monotonic()
            else:
                due += schedule(previous, scan.timestamp, rate)
            previous = scan.timestamp
            pause = due - time.monotonic()
            if pause > 0:
                time.sleep(pause)
            message = convert.laser_scan(scan, self.frame_id, scan_time=0.0)
            if restamp:
                message.header.stamp = convert.stamp_of(time.time())
            if scan.pose is not None:
                stamp = message.header.stamp
                self.tf_writer.write(
                    convert.transform(scan.pose, stamp, self.odom_frame, self.frame_id)
                )
                self.transforms += 1
            self.writer.write(message)
            published += 1
        self.writer.wait_for_acks(int(DRAIN * 1e9))
        if self.transforms:
            self.tf_writer.wait_for_acks(int(DRAIN * 1e9))
        return published
