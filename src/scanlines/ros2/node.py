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
from scanlines.ros2.dds import (
    default_qos,
    participant,
    prepare,
    ros_topic,
    sensor_data_qos,
    take_serialized,
)

__all__ = ["LineNode", "NodeStats"]

#: Scans the reader holds at most (ROS 2 sensor-data depth); DDS overwrites the oldest.
SCAN_DEPTH = 5
#: Latencies kept for the summary (the most recent ones).
MAX_LATENCIES = 100_000
#: Characters of a received ``frame_id`` a log line quotes at most.
MAX_ECHO = 80
#: Characters of an exception's text a log line quotes at most.
MAX_REASON = 200


@dataclass
class NodeStats:
    """What the node did with the samples it took: scans published, malformed scans skipped
    (they decode but are no scan), samples skipped that do not decode as a LaserScan, scans
    that failed (extraction or publishing raised), what Cyclone's SAMPLE_LOST and
    SAMPLE_REJECTED statuses counted, and the latency from taking each scan off the reader
    to its last message written, in seconds."""

    published: int = 0
    skipped: int = 0
    undecodable: int = 0
    failed: int = 0
    full_takes: int = 0
    dds_lost: int = 0
    dds_rejected: int = 0
    latencies: deque = field(default_factory=lambda: deque(maxlen=MAX_LATENCIES))

    def summary(self) -> str:
        """One line: counts and the latency's median and 99th percentile."""
        text = (
            f"{self.published} scans published, {self.skipped} malformed skipped, "
            f"{self.undecodable} undecodable skipped"
        )
        if self.failed:
            text += f", {self.failed} failed"
        if self.dds_lost or self.dds_rejected:
            text += f", DDS reported {self.dds_lost} lost and {self.dds_rejected} rejected"
        if self.full_takes:
            text += f", reader full {self.full_takes} times (older scans dropped by DDS)"
        if self.latencies:
            ms = np.asarray(self.latencies) * 1e3
            text += (
                f"; latency receipt to publish: median {np.median(ms):.2f} ms, "
                f"p99 {np.percentile(ms, 99):.2f} ms"
            )
        return text


def clip(text: str, limit: int = MAX_ECHO) -> str:
    """``text`` quoted for a log line (escapes, no line breaks), its first ``limit``
    characters only: a 1 MB ``frame_id`` from the wire is not echoed whole."""
    if len(text) <= limit:
        return repr(text)
    return f"{text[:limit]!r}... ({len(text):,} chars)"


def _reason(error: BaseException) -> str:
    """An exception as a short one-line reason: its type and the start of its text."""
    words = " ".join(str(error).split())
    if len(words) > MAX_REASON:
        words = words[:MAX_REASON] + "..."
    return f"{type(error).__name__}: {words}" if words else type(error).__name__


class LineNode:
    """Subscribes to ``scan_topic`` (sensor-data QoS) and publishes, per scan, stamped and
    framed as the scan, what laser_line_extraction publishes: its ``LineSegmentList`` on
    ``segments_topic`` and its ``visualization_msgs/Marker`` (one line list) on
    ``markers_topic``; and the project's: a ``visualization_msgs/MarkerArray`` (segments,
    breakpoints, corners) on ``marker_array_topic`` and, with ``features_topic``, the full
    result (``scanlines/msg/ScanFeatures``). A topic of ``None`` is not published.
    Publishers use ROS 2's default QoS (reliable, keep last 10)."""

    def __init__(
        self,
        extractor: Extractor,
        *,
        domain_id: int = 0,
        loopback: bool = False,
        scan_topic: str = "/scan",
        segments_topic: str = "/line_segments",
        markers_topic: str | None = "/line_markers",
        marker_array_topic: str | None = "/scanlines/markers",
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
        prepare(msg.LaserScan, msg.Marker, msg.MarkerArray, msg.LineSegmentList, msg.ScanFeatures)
        dp = participant(domain_id, loopback=loopback)
        self._participant = dp
        writers = {}
        for name, topic, kind in (
            ("segments", segments_topic, msg.LineSegmentList),
            ("markers", markers_topic, msg.Marker),
            ("marker_array", marker_array_topic, msg.MarkerArray),
            ("features", features_topic, msg.ScanFeatures),
        ):
            if topic is not None:
                writers[name] = DataWriter(dp, Topic(dp, ros_topic(topic), kind), default_qos())
        self._writers = writers
        scans = Topic(dp, ros_topic(scan_topic), msg.LaserScan)
        self._reader = DataReader(dp, scans, sensor_data_qos(SCAN_DEPTH))
        self._waitset = WaitSet(dp)
        self._mask = SampleState.Any | ViewState.Any | InstanceState.Any
        self._waitset.attach(ReadCondition(self._reader, self._mask))
        self.localisation = None

    @property
    def participant(self):
        """The node's DDS participant."""
        return self._participant

    def attach(self, localisation) -> None:
        """Localise every scan too (a :class:`~scanlines.ros2.live.LiveLocalisation` on
        :attr:`participant`): its pose is published before the scan's lines, and its
        inputs wake the node as scans do."""
        from cyclonedds.core import ReadCondition

        for reader in localisation.readers:
            self._waitset.attach(ReadCondition(reader, self._mask))
        self.localisation = localisation

    @property
    def writers(self) -> dict:
        """The DataWriters by output (``segments``, ``markers``, ``marker_array``,
        ``features``)."""
        return dict(self._writers)

    def spin(self, *, max_scans: int | None = None, duration: float | None = None) -> NodeStats:
        """Handle samples until ``max_scans`` were handled or ``duration`` seconds passed
        (``None``: until interrupted). Every sample taken counts, decoded or not."""
        deadline = math.inf if duration is None else time.monotonic() + duration
        handled = 0
        try:
            while time.monotonic() < deadline and (max_scans is None or handled < max_scans):
                self._waitset.wait(100_000_000)  # 0.1 s: signals and the deadline are seen
                if self.localisation is not None:
                    self.localisation.poll()
                samples = take_serialized(self._reader, SCAN_DEPTH)
                received = time.perf_counter()
                if len(samples) == SCAN_DEPTH:
                    self.stats.full_takes += 1
                for data, info in samples:
                    if not info.valid_data:  # a publisher's coming or going
                        continue
                    handled += 1
                    message = self.decode(data)
                    if message is not None:
                        self.handle(message, received)
            if self.localisation is not None:
                self.localisation.drain(1.0)
        finally:
            self.read_dds_status()
        return self.stats

    def decode(self, data: bytes) -> msg.LaserScan | None:
        """The LaserScan of one sample's CDR bytes; one that does not decode (a
        ``frame_id`` that is not UTF-8, say) is counted, logged on one line, skipped."""
        try:
            return msg.LaserScan.deserialize(data)
        except Exception as error:  # whatever the bytes make the decoder raise
            self.stats.undecodable += 1
            self._say(
                f"skipped a sample that does not decode as sensor_msgs/LaserScan "
                f"({len(data):,} bytes): {_reason(error)}"
            )
            return None

    def handle(self, message: msg.LaserScan, received: float) -> bool:
        """Extract one scan and publish it; a malformed one is counted, logged, skipped,
        and one whose extraction or publishing raises is counted and logged as failed."""
        header = message.header
        where = (
            f"stamp {header.stamp.sec}.{header.stamp.nanosec:09d}, frame {clip(header.frame_id)}"
        )
        try:
            scan = convert.scan_of(message)
        except ScanError as error:
            self.stats.skipped += 1
            self._say(f"skipped malformed scan ({where}): {error}")
            return False
        try:
            if self.localisation is not None:
                self.localisation.on_scan(scan, header, received)
            self._publish(scan, header)
        except Exception as error:  # no scan ends the node; the count and line show it
            self.stats.failed += 1
            self._say(f"failed on a scan ({where}): {_reason(error)}")
            return False
        self.stats.latencies.append(time.perf_counter() - received)
        self.stats.published += 1
        return True

    def _publish(self, scan, header: msg.Header) -> None:
        extraction = self.extractor(scan)
        writers = self._writers
        if "segments" in writers:
            writers["segments"].write(convert.line_segments(extraction, header))
        if "markers" in writers:
            writers["markers"].write(convert.line_marker(extraction, header))
        if "marker_array" in writers:
            writers["marker_array"].write(convert.markers(extraction, scan, header))
        if "features" in writers:
            writers["features"].write(convert.features(extraction, scan, header))

    def read_dds_status(self) -> None:
        """Copy what Cyclone's SAMPLE_LOST and SAMPLE_REJECTED statuses counted on the scan
        reader into the stats. (Cyclone counts neither a sample it could not deserialise nor
        a fragmented one that lost a fragment: README, "What DDS drops".)"""
        self.stats.dds_lost = self._reader.get_sample_lost_status().total_count
        self.stats.dds_rejected = self._reader.get_sample_rejected_status().total_count

    def _say(self, text: str) -> None:
        print(f"scanlines ros2: {text}", file=self.log, flush=True)
