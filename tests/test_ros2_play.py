"""``scanlines ros2 --play``: a log's scans whose timestamps a ROS 2 time cannot hold."""

import subprocess
import sys

import pytest

pytest.importorskip("cyclonedds")

pytestmark = pytest.mark.slow  # a ROS 2 process over DDS per test

STAMPS = [1.0, -5.0, 2.0, 3e9, 3.0]


def stamped_log(path):
    """A CSV log of five 3-beam scans stamped :data:`STAMPS`."""
    rows = ["# angle_min=-1.0 angle_increment=1.0", "# range_max=10.0", "timestamp,r0,r1,r2"]
    rows += [f"{stamp!r},1.0,2.0,3.0" for stamp in STAMPS]
    path.write_text("\n".join(rows) + "\n")
    return path


def play(log, domain, *args):
    done = subprocess.run(
        [sys.executable, "-m", "scanlines", "ros2", "--play", str(log), "--loopback",
         "--domain-id", str(domain), "--wait", "0", "--rate", "100", *args],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    return done.returncode, done.stderr.strip().splitlines()


def test_a_timestamp_no_ros2_time_can_hold_names_the_log_scan_and_field(tmp_path, dds_domain):
    log = stamped_log(tmp_path / "stamps.csv")
    code, lines = play(log, dds_domain)
    assert code == 2, lines
    assert lines[-1] == (
        f"scanlines: error: {log}, scan index 1, field timestamp: -5.0 s is not a ROS 2 "
        "time (0 .. 2**31 - 1 s); --on-error skip skips such scans"
    )
    assert not any("Traceback" in line for line in lines)


def test_on_error_skip_publishes_the_others_and_counts_the_skipped(tmp_path, dds_domain):
    log = stamped_log(tmp_path / "stamps.csv")
    code, lines = play(log, dds_domain, "--on-error", "skip")
    assert code == 0, lines
    assert lines[-1] == (
        "scanlines ros2: published 3 scans of stamps.csv on /scan; "
        "scan records skipped: 2 (timestamp 2)"
    )


def test_stamps_that_step_back_are_reported_once_and_restamp_makes_them_go_forward(tmp_path):
    """A log stamped 1, 2, 1.5, 3: one line on start says so; ``--restamp`` publishes 1, 2,
    3.25, 4.75 (the log's positive intervals, their median 1.25 s where it steps back);
    without it the log's own stamps go out."""
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from dds_domains import domain_held
    from scanlines.ros2 import messages as msg
    from scanlines.ros2.dds import default_qos, participant, ros_topic

    rows = ["# angle_min=-1.0 angle_increment=1.0", "# range_max=10.0", "timestamp,r0,r1,r2"]
    rows += [f"{stamp!r},1.0,2.0,3.0" for stamp in (1.0, 2.0, 1.5, 3.0)]
    log = tmp_path / "back.csv"
    log.write_text("\n".join(rows) + "\n")
    published = {}
    with domain_held() as domain:
        dp = participant(domain, loopback=True)
        scans = DataReader(dp, Topic(dp, ros_topic("/scan"), msg.LaserScan), default_qos(100))
        for restamp in ((), ("--restamp",)):
            code, lines = play(log, domain, "--wait", "10", *restamp)
            assert code == 0, lines
            assert lines[0] == (
                "scanlines ros2: the log's stamps step back or stand still once (by up to "
                "0.500 s): tf2 and RViz drop or reset on that; "
                + (
                    "publishing --restamp'ed stamps (the log's intervals where positive, the "
                    "median positive interval where a step goes back)"
                    if restamp
                    else "--restamp publishes stamps that only go forward"
                )
            )
            got = [s.header.stamp for s in scans.take(100)]
            published[restamp] = [t.sec + t.nanosec * 1e-9 for t in got]
    assert published[()] == pytest.approx([1.0, 2.0, 1.5, 3.0])
    assert published[("--restamp",)] == pytest.approx([1.0, 2.0, 3.25, 4.75])
