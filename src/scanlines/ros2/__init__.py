"""ROS 2 on the wire without a ROS install: the line-extraction node and a log player (Cyclone DDS).

Needs the ``ros2`` extra (``pip install "scanlines[ros2]"``). :class:`LineNode` subscribes to
a ``sensor_msgs/LaserScan`` topic and publishes markers, laser_line_extraction's
``LineSegmentList`` and optionally the project's ``ScanFeatures``; :class:`Player` publishes
a log's scans. Message types are in :mod:`scanlines.ros2.messages`.
"""

from __future__ import annotations

from scanlines.ros2.dds import LOOPBACK_CONFIG
from scanlines.ros2.node import LineNode, NodeStats
from scanlines.ros2.player import Player

__all__ = ["LOOPBACK_CONFIG", "LineNode", "NodeStats", "Player"]
