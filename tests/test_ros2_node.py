"""The ROS 2 node end to end, over real DDS on the loopback interface, in real processes."""

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

pytest.importorskip("cyclonedds")

from scanlines.data import sample
from scanlines.ros2 import convert
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import default_qos, participant, ros_topic, wait_for_match
from scanlines.ros2.player import SETTLE

pytestmark = pytest.mark.slow  # three processes over DDS per test

SCANS = 40
#: Seconds a node may take to start: imports and kernels from the cache (compiled on a
#: first run, which the CLI tests have usually done).
START = 240.0


def scanlines(*args, **kwargs):
    return subprocess.Popen(
        [sys.executable, "-m", "scanlines", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


def finish(process, timeout=60.0):
    out, err = process.communicate(timeout=timeout)
    return process.returncode, out, err


def reader_of(domain, topic, kind):
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    dp = participant(domain, loopback=True)
    return DataReader(dp, Topic(dp, ros_topic(topic), kind), default_qos(depth=1000))


def take_all(reader, count, timeout):
    """Up to ``count`` samples within ``timeout`` seconds."""
    got, deadline = [], time.monotonic() + timeout
    while len(got) < count and time.monotonic() < deadline:
        got += reader.take(N=count)
        time.sleep(0.01)
    return got


@pytest.fixture(scope="module")
def intel_profile(tmp_path_factory):
    path = tmp_path_factory.mktemp("ros2") / "intel.profile.json"
    done = subprocess.run(
        [sys.executable, "-m", "scanlines", "calibrate", str(sample("intel")), "--out", str(path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return path


@pytest.fixture(scope="module")
def run_records(intel_profile, tmp_path_factory):
    out = tmp_path_factory.mktemp("ros2") / "run.jsonl"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "scanlines",
            "run",
            str(sample("intel")),
            "--scans",
            f":{SCANS}",
            "--sensor-profile",
            str(intel_profile),
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return [json.loads(line) for line in out.read_text().splitlines()]


def test_play_node_subscriber_match_scanlines_run(intel_profile, run_records):
    domain = 61
    segments = reader_of(domain, "/line_segments", msg.LineSegmentList)
    features = reader_of(domain, "/features", msg.ScanFeatures)
    markers = reader_of(domain, "/line_markers", msg.MarkerArray)
    node = scanlines(
        "ros2",
        "--loopback",
        "--domain-id",
        str(domain),
        "--sensor-profile",
        str(intel_profile),
        "--max-scans",
        str(SCANS),
        "--features-topic",
        "/features",
    )
    try:
        assert wait_for_match(segments, START), "the node never published"
        assert wait_for_match(features, 10)
        assert wait_for_match(markers, 10)
        player = scanlines(
            "ros2",
            "--play",
            str(sample("intel")),
            "--scans",
            f":{SCANS}",
            "--rate",
            "40",
            "--loopback",
            "--domain-id",
            str(domain),
        )
        code, _, err = finish(player)
        assert code == 0, err
        got = take_all(segments, SCANS, 30)
        full = take_all(features, SCANS, 10)
        drawn = take_all(markers, SCANS, 10)
        code, _, err = finish(node)
    finally:
        node.kill()
    assert code == 0, err
    assert f"{SCANS} scans published, 0 malformed skipped" in err
    assert "latency receipt to publish: median" in err
    assert len(got) == len(full) == len(drawn) == SCANS == len(run_records)
    for message, extended, shown, record in zip(got, full, drawn, run_records, strict=True):
        assert message.header.frame_id == "laser"
        stamp = message.header.stamp
        assert stamp.sec + stamp.nanosec * 1e-9 == pytest.approx(record["timestamp"], abs=1e-6)
        expected = record["segments"]
        f32 = np.float32
        assert [(s.radius, s.angle, *s.start, *s.end) for s in message.line_segments] == [
            tuple(f32(v) for v in (e["rho"], e["alpha"], *e["start"], *e["end"])) for e in expected
        ]
        assert [(s.first, s.last, s.n_points) for s in extended.segments] == [
            (e["first"], e["last"], e["n_points"]) for e in expected
        ]
        assert extended.breakpoints == record["breakpoints"]
        assert extended.corners == record["corners"]
        assert [m.ns for m in shown.markers] == ["", "segments", "breakpoints", "corners"]
        assert len(shown.markers[1].points) == 2 * len(expected)


def test_malformed_scans_are_counted_and_skipped():
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    domain = 62
    segments = reader_of(domain, "/line_segments", msg.LineSegmentList)
    node = scanlines("ros2", "--loopback", "--domain-id", str(domain), "--max-scans", "3")
    try:
        assert wait_for_match(segments, START)
        dp = participant(domain, loopback=True)
        writer = DataWriter(dp, Topic(dp, ros_topic("/scan"), msg.LaserScan), default_qos())
        assert wait_for_match(writer, 10)
        time.sleep(SETTLE)  # the node's side accepts this writer a moment later
        header = msg.Header(stamp=convert.stamp_of(5.0), frame_id="laser")
        ranges = [2.0] * 181
        writer.write(msg.LaserScan(header, -1.5, 1.5, 3.0 / 180, ranges=ranges[:100]))
        time.sleep(0.05)
        writer.write(msg.LaserScan(header, -1.5, 1.5, float("nan"), ranges=ranges))
        time.sleep(0.05)
        writer.write(msg.LaserScan(header, -1.5, 1.5, 3.0 / 180, range_max=30.0, ranges=ranges))
        got = take_all(segments, 1, 30)
        code, _, err = finish(node)
    finally:
        node.kill()
    assert code == 0, err
    assert len(got) == 1
    skipped = [line for line in err.splitlines() if "skipped malformed scan" in line]
    assert len(skipped) == 2
    assert "ranges has 100 values" in skipped[0]
    assert "angle_increment must be finite" in skipped[1]
    assert "1 scans published, 2 malformed skipped" in err


@pytest.mark.parametrize(
    ("sig", "code", "word"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")],
)
def test_signals_stop_the_node_with_one_line(sig, code, word):
    domain = 63 if sig == signal.SIGINT else 64
    segments = reader_of(domain, "/line_segments", msg.LineSegmentList)
    node = scanlines("ros2", "--loopback", "--domain-id", str(domain), "--duration", "120")
    try:
        assert wait_for_match(segments, START)
        node.send_signal(sig)
        returned, _, err = finish(node, timeout=30)
    finally:
        node.kill()
    assert returned == code, err
    stop_lines = [line for line in err.splitlines() if "listening on /scan" not in line]
    assert len(stop_lines) == 1, err  # the summary rides on it once the node spins
    assert stop_lines[0].startswith(f"scanlines: {word}")
    assert "Traceback" not in err
