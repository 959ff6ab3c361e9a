"""The node's messages on the wire: the CDR bytes of rosbags' ROS 2 serialiser, both ways."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("cyclonedds")

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Nodetype

from scanlines.extractor import Extractor
from scanlines.ros2 import convert
from scanlines.ros2 import messages as msg
from scanlines.scan import Scan


@pytest.fixture(scope="module")
def store():
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    for text_of in (msg.LINE_EXTRACTION_MSGS, msg.SCANLINES_MSGS):
        for name, text in text_of.items():
            typestore.register(get_types_from_msg(text, name))
    return typestore


def ros_name(obj) -> str:
    """``pkg::msg::dds_::Name_`` -> ``pkg/msg/Name``."""
    package, _, _, name = type(obj).__idl_typename__.split("::")
    return f"{package}/msg/{name[:-1]}"


def as_rosbags(obj, store):
    """The rosbags message of a DDS dataclass message, field by field as rosbags types it."""
    name = ros_name(obj)
    values = {}
    for field_name, (kind, spec) in store.fielddefs[name][1]:
        value = getattr(obj, field_name)
        if kind in (Nodetype.SEQUENCE, Nodetype.ARRAY):
            (inner_kind, inner), _ = spec
            if inner_kind == Nodetype.BASE and inner[0] != "string":
                value = np.array(value, dtype=np.dtype(inner[0].replace("bool", "bool_")))
            else:
                value = [as_rosbags(item, store) for item in value]
        elif kind == Nodetype.NAME:
            value = as_rosbags(value, store)
        values[field_name] = value
    return store.types[name](**values)


def assert_same_wire(obj, store):
    """Cyclone's bytes are rosbags' bytes, and Cyclone decodes rosbags' bytes to ``obj``."""
    theirs = bytes(store.serialize_cdr(as_rosbags(obj, store), ros_name(obj)))
    assert theirs[:4] == b"\x00\x01\x00\x00"  # CDR little-endian encapsulation header
    ours = obj.serialize()
    assert ours == theirs
    decoded = type(obj).deserialize(theirs)  # float32 fields hold float32 values now
    assert decoded == type(obj).deserialize(ours)
    assert decoded.serialize() == theirs
    return decoded


float32s = st.floats(width=32, allow_nan=False)
stamps = st.builds(msg.Time, sec=st.integers(0, 2**31 - 1), nanosec=st.integers(0, 999_999_999))
headers = st.builds(msg.Header, stamp=stamps, frame_id=st.text(max_size=12))


@settings(max_examples=60, deadline=None)
@given(
    header=headers,
    ranges=st.lists(st.floats(width=32), max_size=40),
    angles=st.tuples(float32s, float32s, float32s),
    limits=st.tuples(float32s, float32s),
)
def test_laser_scan_both_ways(store, header, ranges, angles, limits):
    ranges = [r for r in ranges if r == r]  # NaN != NaN: equality of messages needs numbers
    scan = msg.LaserScan(header, *angles, 0.0, 0.0, *limits, ranges, ranges[::-1])
    assert assert_same_wire(scan, store) == scan  # every value is a float32 already


def _sample_extraction():
    scan = Scan(
        2.0 + 0.3 * np.sin(np.linspace(0, 9, 181)),
        -np.pi / 2,
        np.pi / 180,
        0.0,
        30.0,
        timestamp=12.5,
    )
    return scan, Extractor()(scan)


@pytest.mark.parametrize("kind", ["segments", "marker", "markers", "features", "tf"])
def test_published_types_serialise_as_rosbags(store, kind):
    scan, extraction = _sample_extraction()
    assert len(extraction.lines) > 0
    header = msg.Header(stamp=convert.stamp_of(12.5), frame_id="laser")
    message = {
        "segments": lambda: convert.line_segments(extraction, header),
        "marker": lambda: convert.line_marker(extraction, header),
        "markers": lambda: convert.markers(extraction, scan, header),
        "features": lambda: convert.features(extraction, scan, header),
        "tf": lambda: convert.transform((1.5, -2.0, 2.5), header.stamp, "odom", "laser"),
    }[kind]()
    assert_same_wire(message, store)


@pytest.mark.parametrize("kind", ["amcl_pose", "grid", "map_markers", "odometry"])
def test_the_localisations_types_serialise_as_rosbags(store, kind):
    """What ``--map`` publishes and ``--play`` sends on ``/odom``: CDR bytes as rosbags'."""
    from scanlines.map.align import LineSet
    from scanlines.map.frame import LocalFrame
    from scanlines.ros2.live import amcl_pose
    from scanlines.ros2.localizer import LivePose
    from scanlines.ros2.map_topics import map_markers, occupancy_grid

    stamp = convert.stamp_of(12.5)
    lines = LineSet(np.zeros(2), np.zeros(2), np.array([[0.0, 0.0], [1.0, -1.0]]),
                    np.array([[2.0, 0.0], [1.0, 1.5]]))  # fmt: skip
    frame = LocalFrame(3.0, -4.0)
    covariance = np.array([[0.01, 0.002, 0.0], [0.002, 0.02, 0.001], [0.0, 0.001, 0.003]])
    live = LivePose(12.5, (1.0, 2.0, 0.5), covariance, (0.1, 0.2, 0.3), (1.0, 2.0, 0.5), "aligned")
    odometry = msg.Odometry(header=msg.Header(stamp=stamp, frame_id="odom"),
                            child_frame_id="base_link")  # fmt: skip
    odometry.pose.pose.position.x = 1.25
    message = {
        "amcl_pose": lambda: amcl_pose(live, stamp, "map"),
        "grid": lambda: occupancy_grid(lines, frame, "map", stamp),
        "map_markers": lambda: map_markers(lines, frame, "map", stamp),
        "odometry": lambda: odometry,
    }[kind]()
    decoded = assert_same_wire(message, store)
    if kind == "amcl_pose":
        cells = np.asarray(decoded.pose.covariance).reshape(6, 6)
        assert np.array_equal(cells[np.ix_([0, 1, 5], [0, 1, 5])], covariance)


def test_the_line_marker_is_laser_line_extractions():
    """One LINE_LIST in namespace line_extraction, id 0, 0.1 m wide, red: the marker
    laser_line_extraction publishes on line_markers, each segment's start and end."""
    _, extraction = _sample_extraction()
    header = msg.Header(stamp=convert.stamp_of(12.5), frame_id="laser")
    marker = convert.line_marker(extraction, header)
    assert (marker.ns, marker.id, marker.type, marker.action) == ("line_extraction", 0, 5, 0)
    assert marker.scale.x == 0.1
    assert (marker.color.r, marker.color.g, marker.color.b, marker.color.a) == (1, 0, 0, 1)
    assert marker.pose.orientation.w == 1.0
    ends = [(p.x, p.y) for p in marker.points]
    assert ends[0::2] == [tuple(row[2:4]) for row in extraction.lines.tolist()]
    assert ends[1::2] == [tuple(row[4:6]) for row in extraction.lines.tolist()]


def test_a_pose_is_a_transform_of_its_yaw():
    stamp = convert.stamp_of(3.25)
    (sent,) = convert.transform((1.0, 2.0, np.pi / 2), stamp, "odom", "laser").transforms
    assert (sent.header.frame_id, sent.child_frame_id, sent.header.stamp) == (
        "odom",
        "laser",
        stamp,
    )
    moved = sent.transform
    assert (moved.translation.x, moved.translation.y, moved.translation.z) == (1.0, 2.0, 0.0)
    rotation = moved.rotation
    assert (rotation.x, rotation.y) == (0.0, 0.0)
    assert (rotation.z, rotation.w) == pytest.approx((np.sqrt(0.5), np.sqrt(0.5)))


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(
            float32s,
            float32s,
            st.lists(float32s, min_size=4, max_size=4),
            st.lists(float32s, min_size=4, max_size=4),
        ),
        max_size=8,
    ),
    headers,
)
def test_line_segment_list_both_ways(store, rows, header):
    segments = [msg.LineSegment(r, a, cov, ends[:2], ends[2:]) for r, a, cov, ends in rows]
    assert_same_wire(msg.LineSegmentList(header, segments), store)


def test_type_names_are_ros2_mangled():
    assert msg.LaserScan.__idl_typename__ == "sensor_msgs::msg::dds_::LaserScan_"
    assert msg.LineSegmentList.__idl_typename__ == (
        "laser_line_extraction::msg::dds_::LineSegmentList_"
    )
    assert msg.MarkerArray.__idl_typename__ == "visualization_msgs::msg::dds_::MarkerArray_"


def test_the_own_messages_are_the_documented_msg_text(store):
    for name in msg.SCANLINES_MSGS:
        ours = msg.Segment if name.endswith("/Segment") else msg.ScanFeatures
        declared = [field for field, _ in store.fielddefs[name][1]]
        assert declared == [f.name for f in dataclasses.fields(ours)]


def test_the_documented_msg_files_are_the_ones_on_the_wire():
    documented = Path(__file__).parents[1] / "docs" / "ros2" / "msg"
    for name, text in msg.SCANLINES_MSGS.items():
        assert (documented / f"{name.rsplit('/', 1)[1]}.msg").read_text() == text
