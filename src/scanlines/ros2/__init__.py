"""ROS 2 on the wire without a ROS install: the line-extraction node and a log player (Cyclone DDS).

Needs the ``ros2`` extra (``pip install ".[ros2]"``). :class:`LineNode` subscribes to a
``sensor_msgs/LaserScan`` topic and publishes laser_line_extraction's ``LineSegmentList``
and ``Marker``, a ``MarkerArray`` and optionally the project's ``ScanFeatures``;
:class:`Player` publishes a log's scans (and its poses on ``/tf``). Message types are in
:mod:`scanlines.ros2.messages`; the ROS arguments (``--ros-args``) in
:mod:`scanlines.ros2.ros_args`, :mod:`scanlines.ros2.names` and
:mod:`scanlines.ros2.parameters`, which need no DDS (the package imports Cyclone DDS only
when one of the names below is used).
"""

from __future__ import annotations

from typing import Any

__all__ = ["LOOPBACK_CONFIG", "LineNode", "NodeStats", "Player"]

_HOMES = {
    "LOOPBACK_CONFIG": "scanlines.ros2.dds",
    "LineNode": "scanlines.ros2.node",
    "NodeStats": "scanlines.ros2.node",
    "Player": "scanlines.ros2.player",
}


def __getattr__(name: str) -> Any:
    if name in _HOMES:
        import importlib

        return getattr(importlib.import_module(_HOMES[name]), name)
    raise AttributeError(f"module 'scanlines.ros2' has no attribute {name!r}")
