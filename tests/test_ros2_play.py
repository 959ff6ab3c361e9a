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
