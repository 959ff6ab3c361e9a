"""The ROS 2 node end to end, over real DDS on the loopback interface, in real processes."""

import io
import json
import pickle
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
#: Seconds a node may take to start (imports and DDS discovery; ample for a loaded machine).
START = 60.0


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


def test_play_node_subscriber_match_scanlines_run(intel_profile, run_records, dds_domain):
    domain = dds_domain
    segments = reader_of(domain, "/line_segments", msg.LineSegmentList)
    features = reader_of(domain, "/features", msg.ScanFeatures)
    markers = reader_of(domain, "/line_markers", msg.Marker)
    marker_arrays = reader_of(domain, "/scanlines/markers", msg.MarkerArray)
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
        assert wait_for_match(marker_arrays, 10)
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
        lines = take_all(markers, SCANS, 10)
        drawn = take_all(marker_arrays, SCANS, 10)
        code, _, err = finish(node)
    finally:
        node.kill()
    assert code == 0, err
    assert f"{SCANS} scans published, 0 malformed skipped" in err
    assert "latency receipt to publish: median" in err
    assert len(got) == len(full) == len(lines) == len(drawn) == SCANS == len(run_records)
    for message, extended, line, shown, record in zip(
        got, full, lines, drawn, run_records, strict=True
    ):
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
        assert line.ns == "line_extraction"
        assert line.header == message.header
        assert [(p.x, p.y) for p in line.points] == [(p.x, p.y) for p in shown.markers[1].points]


def test_malformed_scans_are_counted_and_skipped(dds_domain):
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    domain = dds_domain
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
def test_signals_stop_the_node_with_one_line(sig, code, word, dds_domain):
    domain = dds_domain
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


#: A second participant, in a process of its own: writes the CDR bytes it reads (a pickled
#: list) from stdin as they are, through a LaserScan writer (Cyclone sends a frame_id that is
#: not UTF-8: its writer checks the CDR's layout, not the text).
RAW_WRITER = """
import pickle, sys, time
from cyclonedds._clayer import ddspy_write
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import participant, ros_topic, sensor_data_qos, wait_for_match
payloads = pickle.load(sys.stdin.buffer)
dp = participant(int(sys.argv[1]), loopback=True)
writer = DataWriter(dp, Topic(dp, ros_topic("/scan"), msg.LaserScan), sensor_data_qos())
assert wait_for_match(writer, 30), "no subscriber"
time.sleep(0.5)  # the node's side accepts this writer a moment later
for payload in payloads:
    assert ddspy_write(writer._ref, payload) == 0
time.sleep(0.5)
"""


def write_raw(domain, payloads):
    done = subprocess.run(
        [sys.executable, "-c", RAW_WRITER, str(domain)],
        input=pickle.dumps(payloads),
        capture_output=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr.decode()


def test_a_sample_that_does_not_decode_is_counted_and_the_others_of_its_take_go_on(dds_domain):
    """A frame_id that is not UTF-8 used to raise out of DataReader.take (a traceback, exit
    1), losing the good scan taken with it; and a malformed scan's line quoted its whole
    frame_id."""
    from scanlines.extractor import Extractor
    from scanlines.ros2 import LineNode

    domain = dds_domain
    extractor = Extractor()
    log = io.StringIO()
    node = LineNode(extractor, domain_id=domain, loopback=True, features_topic="/features", log=log)
    features = reader_of(domain, "/features", msg.ScanFeatures)
    header = msg.Header(stamp=convert.stamp_of(5.0), frame_id="laser")
    ranges = [2.0] * 181
    good = msg.LaserScan(header, -1.5, 1.5, 3.0 / 180, range_max=30.0, ranges=ranges).serialize()
    at = good.index(b"laser")
    not_utf8 = good[:at] + b"\xff\xfe\xfd\xfc\xfb" + good[at + 5 :]
    long_frame = msg.Header(stamp=convert.stamp_of(6.0), frame_id="f" * 100_000)
    malformed = msg.LaserScan(long_frame, -1.5, 1.5, 3.0 / 180, ranges=ranges[:100]).serialize()
    write_raw(domain, [not_utf8, good, malformed])  # all three wait on the node's reader
    stats = node.spin(max_scans=3, duration=60)  # so one take has them all
    lines = log.getvalue().splitlines()
    assert (stats.published, stats.undecodable, stats.skipped, stats.failed) == (1, 1, 1, 0), lines
    got = take_all(features, 1, 30)
    assert [m.header.frame_id for m in got] == ["laser"]
    assert len(got[0].segments) > 0
    assert len(lines) == 2, lines
    undecodable, skipped = lines
    assert undecodable.startswith("scanlines ros2: skipped a sample that does not decode as ")
    assert f"({len(not_utf8):,} bytes): UnicodeDecodeError: " in undecodable
    assert skipped.startswith("scanlines ros2: skipped malformed scan (stamp 6.000000000, frame ")
    assert "... (100,000 chars)): ranges has 100 values" in skipped
    assert len(skipped) < 300
    assert "1 scans published, 1 malformed skipped, 1 undecodable skipped" in stats.summary()


def test_million_beam_scans_arrive_over_best_effort_loopback(dds_domain):
    """A million-beam scan (4 MB, some 3,000 fragments in one burst) overflowed Cyclone's
    default 1 MiB socket receive buffer: 2 of 20 arrived. ``--loopback`` asks for 8 MB, which
    needs ``net.core.rmem_max`` of 4 MiB or more (Linux grants no more than it); 4 of 5 must
    arrive (all 40 did in the measurements)."""
    from pathlib import Path

    if int(Path("/proc/sys/net/core/rmem_max").read_text()) < 4 * 2**20:
        pytest.skip("net.core.rmem_max is below 4 MiB: no socket gets the buffer it asks for")
    tool = Path(__file__).parents[1] / "tools" / "benchmarks" / "ros2_sizes.py"
    done = subprocess.run(
        [sys.executable, str(tool), "--beams", "1000000", "--count", "5", "--rate", "5",
         "--domain-id", str(dds_domain)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    row = done.stdout.splitlines()[-1]
    arrived = int(row.split("):", 1)[1].split(" of ")[0])
    assert arrived >= 4, row
