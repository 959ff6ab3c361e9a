"""The line-extraction node: LaserScan in, markers and line segments out, over DDS."""

from __future__ import annotations

import math
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from typing import TextIO

import numpy as np

from scanlines.errors import ScanError
from scanlines.extractor import Extractor
from scanlines.ros2 import convert
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import default_qos, participant, prepare, ros_topic, sensor_data_qos

__all__ = ["LineNode", "NodeStats"]

#: Scans the reader holds at most (ROS 2 sensor-data depth); DDS overwrites the oldest.
SCAN_DEPTH = 5
#: Latencies kept for the summary (the most recent ones).
MAX_LATENCIES = 100_000


@dataclass
class NodeStats:
    """What the node did: scans published, malformed scans skipped, and the latency from
    taking each scan off the reader to its last message written, in seconds."""

    published: int = 0
    skipped: int = 0
    full_takes: int = 0
    latencies: deque = field(default_factory=lambda: deque(maxlen=MAX_LATENCIES))

    def summary(self) -> str:
        """One line: counts and the latency's median and 99th percentile."""
        text = f"{self.published} scans published, {self.skipped} malformed skipped"
        if self.full_takes:
            text += f", reader full {self.full_takes} times (older scans dropped by DDS)"
        if self.latencies:
            ms = np.asarray(self.latencies) * 1e3
            text += (
                f"; latency receipt to publish: median {np.median(ms):.2f} ms, "
                f"p99 {np.percentile(ms, 99):.2f} ms"
            )
        return text


class LineNode:
    """Subscribes to ``scan_topic`` (sensor-data QoS) and publishes, per scan, stamped and
    framed as the scan: ``markers`` (``visualization_msgs/MarkerArray``), ``line_segments``
    (laser_line_extraction's ``LineSegmentList``) and, with ``features``, the full result
    (``scanlines/msg/ScanFeatures`` on ``features_topic``). Publishers use ROS 2's default
    QoS (reliable, keep last 10)."""

    def __init__(
        self,
        extractor: Extractor,
        *,
        domain_id: int = 0,
        loopback: bool = False,
        scan_topic: str = "/scan",
        markers_topic: str = "/line_markers",
        segments_topic: str = "/line_segments",
        features_topic: str | None = None,
        log: TextIO = sys.stderr,
    ) -> None:
        from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        self.extractor = extractor
        self.log = log
        self.stats = NodeStats()
        prepare(msg.LaserScan, msg.MarkerArray, msg.LineSegmentList, msg.ScanFeatures)
        dp = participant(domain_id, loopback=loopback)
        self._participant = dp
        writers = {}
        for name, topic, kind in (
            ("markers", markers_topic, msg.MarkerArray),
            ("segments", segments_topic, msg.LineSegmentList),
            ("features", features_topic, msg.ScanFeatures),
        ):
            if topic is not None:
                writers[name] = DataWriter(dp, Topic(dp, ros_topic(topic), kind), default_qos())
        self._writers = writers
        scans = Topic(dp, ros_topic(scan_topic), msg.LaserScan)
        self._reader = DataReader(dp, scans, sensor_data_qos(SCAN_DEPTH))
        self._waitset = WaitSet(dp)
        mask = SampleState.Any | ViewState.Any | InstanceState.Any
        self._waitset.attach(ReadCondition(self._reader, mask))

    @property
    def writers(self) -> dict:
        """The DataWriters by output (``markers``, ``segments``, ``features``)."""
        return dict(self._writers)

    def spin(self, *, max_scans: int | None = None, duration: float | None = None) -> NodeStats:
        """Handle scans until ``max_scans`` were handled or ``duration`` seconds passed
        (``None``: until interrupted)."""
        deadline = math.inf if duration is None else time.monotonic() + duration
        handled = 0
        while time.monotonic() < deadline and (max_scans is None or handled < max_scans):
            self._waitset.wait(100_000_000)  # 0.1 s: signals and the deadline are seen
            samples = self._reader.take(N=SCAN_DEPTH)
            received = time.perf_counter()
            if len(samples) == SCAN_DEPTH:
                self.stats.full_takes += 1
            for sample in samples:
                if isinstance(sample, msg.LaserScan):  # not a publisher's coming or going
                    self.handle(sample, received)
                    handled += 1
        return self.stats

    def handle(self, message: msg.LaserScan, received: float) -> bool:
        """Extract one scan and publish it; a malformed one is counted, logged, skipped."""
        try:
            scan = convert.scan_of(message)
        except ScanError as error:
            self.stats.skipped += 1
            stamp = message.header.stamp
            print(
                f"scanlines ros2: skipped malformed scan (stamp {stamp.sec}.{stamp.nanosec:09d}, "
                f"frame {message.header.frame_id!r}): {error}",
                file=self.log,
                flush=True,
            )
            return False
        extraction = self.extractor(scan)
        header = message.header
        writers = self._writers
        if "segments" in writers:
            writers["segments"].write(convert.line_segments(extraction, header))
        if "markers" in writers:
            writers["markers"].write(convert.markers(extraction, scan, header))
        if "features" in writers:
            writers["features"].write(convert.features(extraction, scan, header))
        self.stats.latencies.append(time.perf_counter() - received)
        self.stats.published += 1
        return True
