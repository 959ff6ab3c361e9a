"""The node where laser_line_extraction ran, over real DDS on loopback: a ROS user's command
line (remapping, namespace, parameters file, -p), the topics' types, the start-up line, and
``--play``'s ``/tf``. The subscribers here decode the CDR bytes with rosbags' own ROS 2
message definitions, not the node's."""

import subprocess
import sys
import time

import numpy as np
import pytest

pytest.importorskip("cyclonedds")
pytest.importorskip("yaml")

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from dds_domains import domain_held
from scanlines.data import sample
from scanlines.extractor import Extractor
from scanlines.io import open_log
from scanlines.ros2 import Player, convert
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import default_qos, participant, ros_topic, take_serialized, wait_for_match

pytestmark = pytest.mark.slow  # a DDS process or two per test

SCANS = 12
#: Seconds a node may take to start (imports, kernels from the cache).
START = 240.0


@pytest.fixture(scope="module")
def store():
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    for name, text in msg.LINE_EXTRACTION_MSGS.items():
        typestore.register(get_types_from_msg(text, name))
    return typestore


class Subscriber:
    """A reader on ``topic`` in this process that keeps each sample's CDR bytes and decodes
    them with rosbags as ``ros_type``."""

    def __init__(self, domain, topic, kind, ros_type, store):
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        dp = participant(domain, loopback=True)
        self.reader = DataReader(dp, Topic(dp, ros_topic(topic), kind), default_qos(depth=1000))
        self.ros_type, self.store = ros_type, store

    def take(self, count, timeout):
        """Up to ``count`` messages within ``timeout`` seconds, decoded."""
        got, deadline = [], time.monotonic() + timeout
        while len(got) < count and time.monotonic() < deadline:
            got += [data for data, info in take_serialized(self.reader, 1000) if info.valid_data]
            time.sleep(0.01)
        return [self.store.deserialize_cdr(bytes(data), self.ros_type) for data in got]


def scanlines(*args):
    return subprocess.Popen(
        [sys.executable, "-m", "scanlines", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def log_scans(name, count):
    with open_log(sample(name)) as reader:
        return [scan for _, scan in zip(range(count), reader, strict=False)]


@pytest.fixture(scope="module")
def intel_profile(tmp_path_factory):
    path = tmp_path_factory.mktemp("dropin") / "intel.profile.json"
    done = subprocess.run(
        [sys.executable, "-m", "scanlines", "calibrate", str(sample("intel")), "--out", str(path)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return path


def test_a_ros_users_command_line_moves_and_configures_the_node(
    store, intel_profile, tmp_path, dds_domain
):
    """``-r scan:=/front/scan -r __ns:=/robot1 --params-file P -p merge:=false``: the scans
    come from /front/scan (absolute: not under the namespace), the outputs go under
    /robot1 with laser_line_extraction's types, the file's entry for /robot1/scanlines and
    the -p set the extraction, and the start-up line says all of it."""
    domain = dds_domain
    params = tmp_path / "params.yaml"
    params.write_text(
        "scanlines:\n  ros__parameters:\n    method: iepf\n"  # the root namespace's node
        "/robot1/scanlines:\n  ros__parameters:\n"
        f"    min_points: 4\n    sensor_profile: {intel_profile}\n"
    )
    segments = Subscriber(
        domain, "/robot1/line_segments", msg.LineSegmentList,
        "laser_line_extraction/msg/LineSegmentList", store,
    )  # fmt: skip
    markers = Subscriber(
        domain, "/robot1/line_markers", msg.Marker, "visualization_msgs/msg/Marker", store
    )
    arrays = Subscriber(
        domain, "/robot1/scanlines/markers", msg.MarkerArray,
        "visualization_msgs/msg/MarkerArray", store,
    )  # fmt: skip
    node = scanlines(
        "ros2", "--loopback", "--domain-id", str(domain), "--max-scans", str(SCANS),
        "--ros-args", "-r", "scan:=/front/scan", "-r", "__ns:=/robot1",
        "--params-file", str(params), "-p", "merge:=false",
    )  # fmt: skip
    try:
        assert wait_for_match(segments.reader, START), "the node never published"
        assert wait_for_match(markers.reader, 10)
        assert wait_for_match(arrays.reader, 10)
        player = Player(domain_id=domain, loopback=True, topic="/front/scan")
        assert player.wait_for_subscriber(30), "the node does not read /front/scan"
        scans = log_scans("intel", SCANS)
        assert player.play(scans, rate=40) == SCANS
        got = segments.take(SCANS, 30)
        lines = markers.take(SCANS, 10)
        shown = arrays.take(SCANS, 10)
        _, err = node.communicate(timeout=60)
    finally:
        node.kill()
    assert node.returncode == 0, err
    start = err.splitlines()[0]
    assert start.startswith(
        f"scanlines ros2: node /robot1/scanlines (domain {domain}) listening on /front/scan "
        "(LaserScan); method adaptive, merge=False, min_points=4; noise from sensor profile "
        f"{intel_profile} (sigma(r) = "
    ), start
    assert start.endswith(
        "; publishing /robot1/line_segments (LineSegmentList), /robot1/line_markers (Marker), "
        "/robot1/scanlines/markers (MarkerArray)"
    ), start
    assert len(got) == len(lines) == len(shown) == SCANS
    extractor = Extractor(min_points=4, merge=False, sensor_profile=intel_profile)
    for scan, segment_list, line, array in zip(scans, got, lines, shown, strict=True):
        sent = convert.laser_scan(scan, "laser")
        expected = extractor(convert.scan_of(msg.LaserScan.deserialize(sent.serialize())))
        assert len(expected.lines) > 0
        rows = np.asarray(expected.lines[:, :6], dtype=np.float32)
        assert [(s.radius, s.angle, *s.start, *s.end) for s in segment_list.line_segments] == [
            tuple(row) for row in rows.tolist()
        ]
        for header in (segment_list.header, line.header):
            assert header.frame_id == "laser"
            assert (header.stamp.sec, header.stamp.nanosec) == (
                sent.header.stamp.sec,
                sent.header.stamp.nanosec,
            )
        assert (line.ns, line.id, line.type, line.action) == ("line_extraction", 0, 5, 0)
        assert (line.scale.x, line.color.r, line.color.a) == (0.1, 1.0, 1.0)
        ends = [(p.x, p.y) for p in line.points]
        assert ends == [
            (x, y) for row in expected.lines[:, 2:6].tolist() for x, y in (row[:2], row[2:])
        ]
        assert [m.ns for m in array.markers] == ["", "segments", "breakpoints", "corners"]
        assert [(p.x, p.y) for p in array.markers[1].points] == ends


def play(domain, log, *ros_args):
    return scanlines(
        "ros2", "--play", str(sample(log)), "--scans", f":{SCANS}", "--rate", "40",
        "--loopback", "--domain-id", str(domain), "--wait", "60", *ros_args,
    )  # fmt: skip


def test_play_publishes_the_logs_odometry_on_odom_and_tf_and_the_mounting_on_tf_static(
    store, dds_domain
):
    """The log's odometry (the scan's laser pose less the mounting) on /odom and as odom ->
    base_link on /tf, stamped as the scans; the mounting once on /tf_static (transient
    local: a subscriber that comes later gets it), base_link -> laser."""
    from scanlines.geometry.poses import compose

    domain = dds_domain
    tf = Subscriber(domain, "/tf", msg.TFMessage, "tf2_msgs/msg/TFMessage", store)
    odom = Subscriber(domain, "/robot1/odom", msg.Odometry, "nav_msgs/msg/Odometry", store)
    laser = Subscriber(domain, "/robot1/scan", msg.LaserScan, "sensor_msgs/msg/LaserScan", store)
    player = play(domain, "intel", "--ros-args", "-r", "__ns:=/robot1")
    try:
        sent = laser.take(SCANS, 120)
        moved = tf.take(SCANS, 30)
        odometry = odom.take(SCANS, 30)
        _, err = player.communicate(timeout=60)
    finally:
        player.kill()
    assert player.returncode == 0, err
    lines = err.splitlines()
    assert lines[-2:] == [
        "scanlines ros2: the log's odometry on /robot1/odom and /tf as odom -> base_link, "
        "stamped as their scans, the mounting on /tf_static as base_link -> laser; in RViz, "
        "set the fixed frame to odom",
        "scanlines ros2: published 12 scans of intel_excerpt.clf.gz on /robot1/scan and 12 "
        "odometry poses odom -> base_link on /robot1/odom and /tf",
    ]
    assert len(sent) == len(moved) == len(odometry) == SCANS
    with open_log(sample("intel")) as reader:
        next(iter(reader))
        mounting = reader.recorded_mounting
    for scan, message, tf_message, odom_message in zip(
        log_scans("intel", SCANS), sent, moved, odometry, strict=True
    ):
        (transform,) = tf_message.transforms
        assert transform.header.frame_id == odom_message.header.frame_id == "odom"
        assert transform.child_frame_id == odom_message.child_frame_id == "base_link"
        assert message.header.frame_id == "laser"
        assert transform.header.stamp == message.header.stamp == odom_message.header.stamp
        stamp = message.header.stamp
        assert stamp.sec + stamp.nanosec * 1e-9 == pytest.approx(scan.timestamp, abs=1e-6)
        shift, turn = transform.transform.translation, transform.transform.rotation
        position = odom_message.pose.pose.position
        assert (position.x, position.y, position.z) == (shift.x, shift.y, 0.0)
        assert (turn.x, turn.y) == (0.0, 0.0)
        base = (shift.x, shift.y, 2 * np.arctan2(turn.z, turn.w))
        assert compose(base, mounting) == pytest.approx(scan.pose, abs=1e-9)


def test_play_publishes_the_mounting_on_tf_static_for_later_subscribers(store):
    with domain_held() as domain:
        got, err, code = _late_static(store, domain)
    assert code == 0, err
    (data,) = got
    (transform,) = store.deserialize_cdr(bytes(data), "tf2_msgs/msg/TFMessage").transforms
    assert (transform.header.frame_id, transform.child_frame_id) == ("base_link", "laser")


def _late_static(store, domain):
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from scanlines.ros2.dds import latched_qos

    laser = Subscriber(domain, "/scan", msg.LaserScan, "sensor_msgs/msg/LaserScan", store)
    player = play(domain, "intel")
    try:
        assert len(laser.take(SCANS, 120)) == SCANS
        dp = participant(domain, loopback=True)  # a subscriber after the mounting was sent
        late = DataReader(dp, Topic(dp, ros_topic("/tf_static"), msg.TFMessage), latched_qos())
        got, deadline = [], time.monotonic() + 10
        while not got and time.monotonic() < deadline:
            got = [d for d, info in take_serialized(late, 10) if info.valid_data]
            time.sleep(0.05)
        _, err = player.communicate(timeout=60)
    finally:
        player.kill()
    return got, err, player.returncode


def test_play_of_a_log_without_poses_says_why_there_is_no_tf(store, dds_domain):
    domain = dds_domain
    tf = Subscriber(domain, "/tf", msg.TFMessage, "tf2_msgs/msg/TFMessage", store)
    laser = Subscriber(domain, "/scan", msg.LaserScan, "sensor_msgs/msg/LaserScan", store)
    player = play(domain, "urg")
    try:
        sent = laser.take(SCANS, 120)
        _, err = player.communicate(timeout=60)
        moved = tf.take(1, 1.0)
    finally:
        player.kill()
    assert player.returncode == 0, err
    assert err.splitlines() == [
        "scanlines ros2: no /tf: urg_excerpt.dat.gz has no poses; in RViz, set the fixed "
        "frame to laser",
        "scanlines ros2: published 12 scans of urg_excerpt.dat.gz on /scan",
    ]
    assert len(sent) == SCANS
    assert moved == []
