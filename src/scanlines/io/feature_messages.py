"""The project's own ROS 2 messages, a scan's whole result, as ``.msg`` definitions.

Bags and MCAP files (:mod:`scanlines.io.bag_writer`) and the ROS 2 node
(:mod:`scanlines.ros2`) publish ``scanlines/msg/ScanFeatures``; its definition travels
with it (the bag's connection, the MCAP schema), and the same text is in
``docs/ros2/msg/`` for a ROS 2 package that builds it.
"""

from __future__ import annotations

from typing import Any

__all__ = ["FEATURE_MSGS", "register_feature_messages"]

FEATURE_MSGS = {
    "scanlines/msg/Segment": (
        "# One fitted segment (scanlines.Segment); first > last: it crosses a full circle's seam\n"
        "int32 first\nint32 last\nuint32 n_points\n"
        "# Hesse form x cos(angle) + y sin(angle) = radius, radius >= 0\n"
        "float32 radius\nfloat32 angle\n"
        "# row-major 2 x 2 covariance of (radius, angle)\n"
        "float32[4] covariance\nfloat32[2] start\nfloat32[2] end\nfloat32 rms\n"
        "# what ends it: index into corner, jump, occluded, gap, edge, open\n"
        "uint8 start_kind\nuint8 end_kind\n"
    ),
    "scanlines/msg/ScanFeatures": (
        "std_msgs/Header header\nstring method\nscanlines/Segment[] segments\n"
        "# beam indices\nint32[] breakpoints\nint32[] corners\nint32[] outliers\n"
        "# the breakpoints' and corners' returns in header.frame_id (z = 0)\n"
        "geometry_msgs/Point[] breakpoint_points\ngeometry_msgs/Point[] corner_points\n"
    ),
}
"""``.msg`` text by ROS 2 type name, dependencies first."""


def register_feature_messages(typestore: Any) -> None:
    """Add :data:`FEATURE_MSGS` to a rosbags typestore (ROS 2 Humble or later)."""
    from rosbags.typesys import get_types_from_msg

    for name, text in FEATURE_MSGS.items():
        typestore.register(get_types_from_msg(text, name))
