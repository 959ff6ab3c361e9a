"""Writing small ROS 1 / ROS 2 bags of LaserScan messages with rosbags, for the tests."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore

from scanlines.scan import Scan

LASERSCAN = "sensor_msgs/msg/LaserScan"


def stamp_parts(seconds: float) -> tuple[int, int]:
    sec = math.floor(seconds)
    return sec, round((seconds - sec) * 1e9)


def laser_scan_message(store, scan: Scan, seconds: float | None, *, ros1: bool, seq: int = 0):
    types = store.types
    sec, nanosec = (0, 0) if seconds is None else stamp_parts(seconds)
    stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
    header_fields = {"stamp": stamp, "frame_id": "laser"} | ({"seq": seq} if ros1 else {})
    n = len(scan)
    return types[LASERSCAN](
        header=types["std_msgs/msg/Header"](**header_fields),
        angle_min=scan.angle_min,
        angle_max=scan.angle_min + (n - 1) * scan.angle_increment,
        angle_increment=scan.angle_increment,
        time_increment=0.0,
        scan_time=0.0,
        range_min=scan.range_min,
        range_max=scan.range_max,
        ranges=np.asarray(scan.ranges, dtype=np.float32),
        intensities=np.arange(n, dtype=np.float32),
    )


def write_bag(
    path: Path,
    kind: str,
    scans: Sequence[Scan],
    *,
    topics: Sequence[str] = ("/scan",),
    string_topic: str | None = None,
    zero_stamps: bool = False,
    chunk_bytes: int | None = None,
    compression: str | None = None,
) -> None:
    """Write ``scans`` to every topic in ``topics`` (and strings to ``string_topic``).

    ``chunk_bytes`` (ROS 1): start a new chunk past this many bytes (rosbags: 1 MiB);
    ``compression`` (ROS 1): ``"bz2"`` or ``"lz4"`` chunks.

    ``kind`` is ``"ros1"``, ``"sqlite3"`` or ``"mcap"``. Bag time is the scan time
    plus 1000 s, so a reader using the header stamp can be told apart.
    """
    ros1 = kind == "ros1"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    if ros1:
        writer = Writer1(path)
        if chunk_bytes is not None:
            writer.chunk_threshold = chunk_bytes
        if compression is not None:
            writer.set_compression(getattr(Writer1.CompressionFormat, compression.upper()))
    else:
        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    with writer:
        connections = [writer.add_connection(t, LASERSCAN, typestore=store) for t in topics]
        text = None
        if string_topic:
            text = writer.add_connection(string_topic, "std_msgs/msg/String", typestore=store)
        for index, scan in enumerate(scans):
            bag_ns = int((scan.timestamp + 1000.0) * 1e9)
            stamp = None if zero_stamps else scan.timestamp
            message = laser_scan_message(store, scan, stamp, ros1=ros1, seq=index)
            for connection in connections:
                writer.write(connection, bag_ns, serialize(message, LASERSCAN))
            if text is not None:
                note = store.types["std_msgs/msg/String"](data=f"scan {index}")
                writer.write(text, bag_ns, serialize(note, "std_msgs/msg/String"))
