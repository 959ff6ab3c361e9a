"""The ROS 2 messages on the wire, as Cyclone DDS IDL dataclasses named as ROS 2 mangles them.

Each class is a ROS 2 message type: ``typename`` is ROS 2's DDS name for it
(``pkg::msg::dds_::Name_``), fields in the order of the ``.msg`` file, so the CDR bytes are
those a ROS 2 node sends and decodes. ``sensor_msgs``, ``std_msgs``, ``geometry_msgs``,
``builtin_interfaces``, ``visualization_msgs``, ``nav_msgs`` and ``tf2_msgs`` follow ROS 2
Humble;
``LineSegment`` and ``LineSegmentList`` are laser_line_extraction's; ``Segment`` and
``ScanFeatures`` are the project's own (:data:`SCANLINES_MSGS`).
"""

# No `from __future__ import annotations`: the IDL layer resolves the annotations as objects.
from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float32, float64, int8, int32, sequence, uint8, uint32

from scanlines.io.feature_messages import FEATURE_MSGS

__all__ = [
    "LINE_EXTRACTION_MSGS",
    "SCANLINES_MSGS",
    "ColorRGBA",
    "CompressedImage",
    "Duration",
    "Header",
    "LaserScan",
    "LineSegment",
    "LineSegmentList",
    "MapMetaData",
    "Marker",
    "MarkerArray",
    "MeshFile",
    "OccupancyGrid",
    "Odometry",
    "Point",
    "Pose",
    "PoseWithCovariance",
    "PoseWithCovarianceStamped",
    "Quaternion",
    "ScanFeatures",
    "Segment",
    "TFMessage",
    "Time",
    "Transform",
    "TransformStamped",
    "Twist",
    "TwistWithCovariance",
    "UVCoordinate",
    "Vector3",
]


def _dds(name: str) -> str:
    """ROS 2's DDS type name of ``pkg/msg/Name``: ``pkg::msg::dds_::Name_``."""
    package, _, message = name.split("/")
    return f"{package}::msg::dds_::{message}_"


@dataclass
class Time(IdlStruct, typename=_dds("builtin_interfaces/msg/Time")):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Duration(IdlStruct, typename=_dds("builtin_interfaces/msg/Duration")):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename=_dds("std_msgs/msg/Header")):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class LaserScan(IdlStruct, typename=_dds("sensor_msgs/msg/LaserScan")):
    header: Header = field(default_factory=Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: sequence[float32] = field(default_factory=list)
    intensities: sequence[float32] = field(default_factory=list)


@dataclass
class Point(IdlStruct, typename=_dds("geometry_msgs/msg/Point")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename=_dds("geometry_msgs/msg/Quaternion")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose(IdlStruct, typename=_dds("geometry_msgs/msg/Pose")):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class Vector3(IdlStruct, typename=_dds("geometry_msgs/msg/Vector3")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class ColorRGBA(IdlStruct, typename=_dds("std_msgs/msg/ColorRGBA")):
    r: float32 = 0.0
    g: float32 = 0.0
    b: float32 = 0.0
    a: float32 = 0.0


@dataclass
class CompressedImage(IdlStruct, typename=_dds("sensor_msgs/msg/CompressedImage")):
    header: Header = field(default_factory=Header)
    format: str = ""
    data: sequence[uint8] = field(default_factory=list)


@dataclass
class UVCoordinate(IdlStruct, typename=_dds("visualization_msgs/msg/UVCoordinate")):
    u: float32 = 0.0
    v: float32 = 0.0


@dataclass
class MeshFile(IdlStruct, typename=_dds("visualization_msgs/msg/MeshFile")):
    filename: str = ""
    data: sequence[uint8] = field(default_factory=list)


@dataclass
class Marker(IdlStruct, typename=_dds("visualization_msgs/msg/Marker")):
    LINE_LIST = 5
    SPHERE_LIST = 7
    ADD = 0
    DELETEALL = 3

    header: Header = field(default_factory=Header)
    ns: str = ""
    id: int32 = 0
    type: int32 = 0
    action: int32 = 0
    pose: Pose = field(default_factory=Pose)
    scale: Vector3 = field(default_factory=Vector3)
    color: ColorRGBA = field(default_factory=ColorRGBA)
    lifetime: Duration = field(default_factory=Duration)
    frame_locked: bool = False
    points: sequence[Point] = field(default_factory=list)
    colors: sequence[ColorRGBA] = field(default_factory=list)
    texture_resource: str = ""
    texture: CompressedImage = field(default_factory=CompressedImage)
    uv_coordinates: sequence[UVCoordinate] = field(default_factory=list)
    text: str = ""
    mesh_resource: str = ""
    mesh_file: MeshFile = field(default_factory=MeshFile)
    mesh_use_embedded_materials: bool = False


@dataclass
class MarkerArray(IdlStruct, typename=_dds("visualization_msgs/msg/MarkerArray")):
    markers: sequence[Marker] = field(default_factory=list)


@dataclass
class Transform(IdlStruct, typename=_dds("geometry_msgs/msg/Transform")):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename=_dds("geometry_msgs/msg/TransformStamped")):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass
class TFMessage(IdlStruct, typename=_dds("tf2_msgs/msg/TFMessage")):
    transforms: sequence[TransformStamped] = field(default_factory=list)


def _zeros36() -> list[float]:
    return [0.0] * 36


@dataclass
class PoseWithCovariance(IdlStruct, typename=_dds("geometry_msgs/msg/PoseWithCovariance")):
    pose: Pose = field(default_factory=Pose)
    covariance: array[float64, 36] = field(default_factory=_zeros36)


@dataclass
class PoseWithCovarianceStamped(
    IdlStruct, typename=_dds("geometry_msgs/msg/PoseWithCovarianceStamped")
):
    header: Header = field(default_factory=Header)
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)


@dataclass
class Twist(IdlStruct, typename=_dds("geometry_msgs/msg/Twist")):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class TwistWithCovariance(IdlStruct, typename=_dds("geometry_msgs/msg/TwistWithCovariance")):
    twist: Twist = field(default_factory=Twist)
    covariance: array[float64, 36] = field(default_factory=_zeros36)


@dataclass
class Odometry(IdlStruct, typename=_dds("nav_msgs/msg/Odometry")):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@dataclass
class MapMetaData(IdlStruct, typename=_dds("nav_msgs/msg/MapMetaData")):
    map_load_time: Time = field(default_factory=Time)
    resolution: float32 = 0.0
    width: uint32 = 0
    height: uint32 = 0
    origin: Pose = field(default_factory=Pose)


@dataclass
class OccupancyGrid(IdlStruct, typename=_dds("nav_msgs/msg/OccupancyGrid")):
    header: Header = field(default_factory=Header)
    info: MapMetaData = field(default_factory=MapMetaData)
    data: sequence[int8] = field(default_factory=list)


#: laser_line_extraction's messages, as its ``msg/`` files define them.
LINE_EXTRACTION_MSGS = {
    "laser_line_extraction/msg/LineSegment": (
        "float32 radius\nfloat32 angle\nfloat32[4] covariance\nfloat32[2] start\nfloat32[2] end\n"
    ),
    "laser_line_extraction/msg/LineSegmentList": (
        "std_msgs/Header header\nlaser_line_extraction/LineSegment[] line_segments\n"
    ),
}


@dataclass
class LineSegment(IdlStruct, typename=_dds("laser_line_extraction/msg/LineSegment")):
    radius: float32 = 0.0
    angle: float32 = 0.0
    covariance: array[float32, 4] = field(default_factory=lambda: [0.0] * 4)
    start: array[float32, 2] = field(default_factory=lambda: [0.0] * 2)
    end: array[float32, 2] = field(default_factory=lambda: [0.0] * 2)


@dataclass
class LineSegmentList(IdlStruct, typename=_dds("laser_line_extraction/msg/LineSegmentList")):
    header: Header = field(default_factory=Header)
    line_segments: sequence[LineSegment] = field(default_factory=list)


#: The project's messages (``scanlines/msg/...``): a scan's full result.
SCANLINES_MSGS = FEATURE_MSGS


@dataclass
class Segment(IdlStruct, typename=_dds("scanlines/msg/Segment")):
    first: int32 = 0
    last: int32 = 0
    n_points: uint32 = 0
    radius: float32 = 0.0
    angle: float32 = 0.0
    covariance: array[float32, 4] = field(default_factory=lambda: [0.0] * 4)
    start: array[float32, 2] = field(default_factory=lambda: [0.0] * 2)
    end: array[float32, 2] = field(default_factory=lambda: [0.0] * 2)
    rms: float32 = 0.0
    start_kind: uint8 = 0
    end_kind: uint8 = 0


@dataclass
class ScanFeatures(IdlStruct, typename=_dds("scanlines/msg/ScanFeatures")):
    header: Header = field(default_factory=Header)
    method: str = ""
    segments: sequence[Segment] = field(default_factory=list)
    breakpoints: sequence[int32] = field(default_factory=list)
    corners: sequence[int32] = field(default_factory=list)
    outliers: sequence[int32] = field(default_factory=list)
    breakpoint_points: sequence[Point] = field(default_factory=list)
    corner_points: sequence[Point] = field(default_factory=list)
