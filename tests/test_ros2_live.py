"""``scanlines ros2 --map``: live localisation over real DDS on loopback, the shipped Intel
excerpt played with ``--play --restamp`` into the node, an initial pose as RViz sends it,
AMCL's topics read back by a participant of this process that decodes the CDR bytes with
rosbags' own ROS 2 message definitions."""

import math
import subprocess
import sys
import time

import numpy as np
import pytest

pytest.importorskip("cyclonedds")

from rosbags.typesys import Stores, get_typestore

from dds_domains import domain_held
from scanlines.data import sample
from scanlines.geometry.poses import compose, invert
from scanlines.io import open_log
from scanlines.map.filter import INITIAL_SIGMA
from scanlines.map.localize import localize, read_line_map
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import (
    default_qos,
    latched_qos,
    participant,
    ros_topic,
    take_serialized,
    wait_for_match,
)
from scanlines.ros2.map_topics import rasterise
from scanlines.ros2.player import monotonic_stamps

pytestmark = pytest.mark.slow  # DDS processes

#: Seconds a node may take to start (imports, kernels from the cache).
START = 240.0
#: The agreement asked of every scan's amcl_pose with localize's pose (metres).
AGREEMENT = 0.01


@pytest.fixture(scope="module")
def store():
    return get_typestore(Stores.ROS2_HUMBLE)


@pytest.fixture(scope="module")
def intel_map(tmp_path_factory):
    path = tmp_path_factory.mktemp("live") / "intel.json"
    done = subprocess.run(
        [sys.executable, "-m", "scanlines", "map", str(sample("intel")), "--align",
         "--out", str(path)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return path


@pytest.fixture(scope="module")
def intel():
    """The excerpt's scans and the laser's mounting its CARMEN records give."""
    with open_log(sample("intel")) as reader:
        scans = list(reader)
        mounting = reader.recorded_mounting
    return scans, mounting


class Subscriber:
    """A reader in this process keeping each sample's CDR bytes, decoded with rosbags."""

    def __init__(self, domain, topic, kind, ros_type, store, qos=None):
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        dp = participant(domain, loopback=True)
        qos = qos or default_qos(depth=10_000)
        self.reader = DataReader(dp, Topic(dp, ros_topic(topic), kind), qos)
        self.ros_type, self.store, self.got = ros_type, store, []

    def take(self, count, timeout):
        deadline = time.monotonic() + timeout
        while len(self.got) < count and time.monotonic() < deadline:
            self.got += [d for d, info in take_serialized(self.reader, 10_000) if info.valid_data]
            time.sleep(0.01)
        return [self.store.deserialize_cdr(bytes(d), self.ros_type) for d in self.got]


def scanlines(*args):
    return subprocess.Popen([sys.executable, "-m", "scanlines", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip


def initial_pose_writer(domain):
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    dp = participant(domain, loopback=True)
    topic = Topic(dp, ros_topic("/initialpose"), msg.PoseWithCovarianceStamped)
    return DataWriter(dp, topic, default_qos())


def rviz_pose(pose, stamp, sigma):
    """``/initialpose`` as RViz's "2D Pose Estimate" sends it (frame map)."""
    x, y, theta = pose
    covariance = [0.0] * 36
    covariance[0] = covariance[7] = sigma[0] ** 2
    covariance[35] = sigma[1] ** 2
    sec, nanosec = divmod(round(stamp * 1e9), 1_000_000_000)
    return msg.PoseWithCovarianceStamped(
        header=msg.Header(stamp=msg.Time(sec, nanosec), frame_id="map"),
        pose=msg.PoseWithCovariance(
            pose=msg.Pose(msg.Point(x, y, 0.0),
                          msg.Quaternion(0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2))),
            covariance=covariance,
        ),
    )  # fmt: skip


def yaw(q):
    return 2 * math.atan2(q.z, q.w)


def run_live(domain, map_path, scans, mounting, count, sigma, *node_args):
    """The node on ``map_path``, an initial pose (the first scan's, base frame, ``sigma``),
    then ``--play --restamp`` of the excerpt's first ``count`` scans; what came back."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    poses = Subscriber(domain, "/amcl_pose", msg.PoseWithCovarianceStamped,
                       "geometry_msgs/msg/PoseWithCovarianceStamped", store)  # fmt: skip
    tf = Subscriber(domain, "/tf", msg.TFMessage, "tf2_msgs/msg/TFMessage", store)
    grid = Subscriber(domain, "/map", msg.OccupancyGrid, "nav_msgs/msg/OccupancyGrid", store,
                      latched_qos())  # fmt: skip
    markers = Subscriber(domain, "/scanlines/map_markers", msg.MarkerArray,
                         "visualization_msgs/msg/MarkerArray", store, latched_qos())  # fmt: skip
    node = scanlines("ros2", "--map", str(map_path), "--loopback", "--domain-id", str(domain),
                     "--max-scans", str(count), "--duration", "150", *node_args)  # fmt: skip
    player = None
    try:
        initial = initial_pose_writer(domain)
        assert wait_for_match(initial, START), "the node did not subscribe to /initialpose"
        time.sleep(0.5)
        start = compose(scans[0].pose, invert(mounting))
        initial.write(rviz_pose(start, scans[0].timestamp, sigma))
        initial.wait_for_acks(int(5e9))
        player = scanlines("ros2", "--play", str(sample("intel")), "--restamp", "--scans",
                           f":{count}", "--rate", "40", "--loopback", "--domain-id",
                           str(domain), "--wait", "60")  # fmt: skip
        got = poses.take(count, 120)
        moved = tf.take(10 * count, 5)
        _, played = player.communicate(timeout=120)
        _, err = node.communicate(timeout=60)
        maps, arrays = grid.take(1, 10), markers.take(1, 10)
    finally:
        node.kill()
        if player is not None:
            player.kill()
    assert node.returncode == 0, err
    assert player.returncode == 0, played
    return got, moved, maps, arrays, err, played


def test_the_node_localises_each_scan_as_localize_does_and_says_so_as_amcl(store, intel_map, intel):
    """Every scan's amcl_pose within 1 cm of ``localize``'s pose for the same scan (the
    laser's pose less the mounting), stamped with the scan's restamped stamp; ``map ->
    odom`` on /tf composes with the odometry to it; the map on /map and as markers."""
    scans, mounting = intel
    count = min(len(scans), 600)
    lines, frame = read_line_map(intel_map)
    with domain_held() as domain:
        got, moved, maps, arrays, err, played = run_live(
            domain, intel_map, scans, mounting, count, INITIAL_SIGMA
        )
    assert len(got) == count, err
    expected = localize(enumerate(scans[:count]), lines, frame,
                        (scans[0].timestamp, scans[0].pose))  # fmt: skip
    stamps = monotonic_stamps([scan.timestamp for scan in scans[:count]])
    errors = []
    for message, want, stamp in zip(got, expected.tracked, stamps, strict=True):
        assert message.header.frame_id == "map"
        assert message.header.stamp.sec + message.header.stamp.nanosec * 1e-9 == pytest.approx(
            stamp, abs=1e-6
        )
        p = message.pose.pose
        base = compose(frame.world_pose(want.pose), invert(mounting))
        errors.append(math.hypot(p.position.x - base[0], p.position.y - base[1]))
        assert abs(math.remainder(yaw(p.orientation) - base[2], math.tau)) < 1e-3
        covariance = np.asarray(message.pose.covariance).reshape(6, 6)
        assert covariance[0, 0] > 0
        assert covariance[5, 5] > 0
        assert covariance[2, 2] == 0
    assert max(errors) < AGREEMENT
    # map -> odom, dated ahead as AMCL's, composed with the odometry, is the pose
    to_odom = [t for m in moved for t in m.transforms if t.child_frame_id == "odom"]
    assert len(to_odom) == count
    for transform, message, scan in zip(to_odom, got, scans, strict=False):
        assert transform.header.frame_id == "map"
        shift, turn = transform.transform.translation, transform.transform.rotation
        odometry = compose(scan.pose, invert(mounting))
        x, y, _ = compose((shift.x, shift.y, yaw(turn)), odometry)
        assert (x, y) == pytest.approx(
            (message.pose.pose.position.x, message.pose.pose.position.y), abs=1e-6
        )
    (grid,) = maps
    assert grid.header.frame_id == "map"
    assert grid.info.resolution == pytest.approx(0.05)
    cells, (x0, y0) = rasterise(lines, frame)
    assert (grid.info.height, grid.info.width) == cells.shape
    assert (grid.info.origin.position.x, grid.info.origin.position.y) == (x0, y0)
    assert np.array_equal(np.asarray(grid.data, dtype=np.int8), cells.ravel())
    (array,) = arrays
    (marker,) = array.markers
    assert marker.type == msg.Marker.LINE_LIST
    assert len(marker.points) == 2 * len(lines.rho)
    assert f"{count} scans localised" in err.splitlines()[-1]
    assert "latency scan to pose: median" in err.splitlines()[-1]
    assert any("step back" in line and "--restamp'ed" in line for line in played.splitlines())


def test_odometry_from_tf_and_rvizs_covariance(store, intel_map, intel):
    """``--odometry tf``: the odometry from /tf (odom -> base_link); the initial pose's
    covariance (RViz's 0.5 m and 15 deg) is the filter's prior, as localize's would be."""
    scans, mounting = intel
    count = 200
    sigma = (0.5, math.radians(15.0))
    lines, frame = read_line_map(intel_map)
    with domain_held() as domain:
        got, *_, err, _ = run_live(domain, intel_map, scans, mounting, count, sigma,
                                   "--odometry", "tf")  # fmt: skip
    assert len(got) == count, err
    expected = localize(enumerate(scans[:count]), lines, frame,
                        (scans[0].timestamp, scans[0].pose), initial_sigma=sigma)  # fmt: skip
    for message, want in zip(got, expected.tracked, strict=True):
        base = compose(frame.world_pose(want.pose), invert(mounting))
        p = message.pose.pose.position
        assert math.hypot(p.x - base[0], p.y - base[1]) < AGREEMENT


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--map", "nothere.json"], "nothere.json: no such file or directory"),
        (["--map", "MAP", "--initial-pose", "1,2"],
         "--initial-pose: '1,2' is not X,Y,YAW (three finite numbers: metres, metres, radians)"),
        (["--map", "MAP", "--odometry", "wheels"], "--odometry must be odom or tf, got 'wheels'"),
        (["--map", "MAP", "--ros-args", "-p", "base_frame_id:=''"],
         "--ros-args: parameter base_frame_id (-p base_frame_id:=''): a frame's name, got an "
         "empty string"),
    ],
)  # fmt: skip
def test_a_bad_live_option_is_one_line_before_any_dds(intel_map, tmp_path, args, message):
    args = [str(intel_map) if a == "MAP" else a for a in args]
    done = subprocess.run(
        [sys.executable, "-m", "scanlines", "ros2", "--loopback", "--duration", "1", *args],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines() == [f"scanlines: error: {message}"]
