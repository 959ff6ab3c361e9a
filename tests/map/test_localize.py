"""Localisation on a saved line map (scanlines.map.localize, ``scanlines localize``): a
simulated room mapped from true poses, then tracked with drifting odometry from a given
pose; scans before the initial time skipped, a scan that does not fit reported."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cli_helpers import scanlines
from scanlines import Scan
from scanlines.data import sample
from scanlines.evaluation.trajectory import load_trajectory, match_times
from scanlines.io import open_log
from scanlines.map import build_map
from scanlines.map.align import LineSet
from scanlines.map.localize import MapFileError, localize, read_line_map
from test_map import view
from test_map_align import ROOM
from test_map_tracking import drifting_log


def room_map(tmp_path):
    """The map of ROOM from scans at their true poses, written as JSON and read back."""
    from scanlines.map.export import write_map

    truth = [(-2.0 + 0.2 * k, 0.6 * math.sin(k / 4), 0.3 * math.cos(k / 5)) for k in range(20)]
    scans = [view(ROOM, pose, seed=200 + k, sigma=0.003) for k, pose in enumerate(truth)]
    build = build_map(enumerate(scans))
    path = tmp_path / "room.json"
    write_map(build.line_map.lines(), path, overwrite=False)
    return path


def test_drifting_odometry_is_tracked_on_a_saved_map(tmp_path):
    lines, frame = read_line_map(room_map(tmp_path))
    scans, truth = drifting_log()
    start = 10
    run = localize(enumerate(scans), lines, frame, (scans[start].timestamp, tuple(truth[start])))
    assert run.skipped == start
    assert len(run.tracked) == len(scans) - start
    assert run.not_fit == 0
    poses = np.array([frame.world_pose(t.pose) for t in run.tracked])
    odometry = np.array([t.odometry for t in run.tracked])
    error = np.linalg.norm(poses[:, :2] - truth[start:, :2], axis=1)
    assert error.max() < 0.03
    drift = np.linalg.norm(
        odometry[:, :2] - odometry[0, :2] - (truth[start:, :2] - truth[start, :2]), axis=1
    )
    assert drift.max() > 0.2  # what the odometry alone would have given
    sigma = np.sqrt(np.array([t.covariance[0, 0] for t in run.tracked]))
    assert np.all(sigma < 0.02)


def test_a_scan_that_does_not_fit_is_reported_not_forced(tmp_path):
    lines, frame = read_line_map(room_map(tmp_path))
    scans, truth = drifting_log(40)
    box = [((-1.0, -1.0), (1.0, -1.0)), ((1.0, -1.0), (1.0, 1.0))]
    odd = view(box, (0.0, 0.0, 0.0), seed=5, sigma=0.003)
    scans[20] = Scan(odd.ranges, odd.angle_min, odd.angle_increment, pose=scans[20].pose,
                     timestamp=scans[20].timestamp)  # fmt: skip
    run = localize(enumerate(scans), lines, frame, (scans[0].timestamp, tuple(truth[0])))
    assert run.not_fit == 1
    assert run.tracked[20].status == "did not fit"
    # Its pose is the prediction, less certain than its neighbours'.
    assert run.tracked[20].pose == run.tracked[20].predicted
    assert run.tracked[20].covariance[0, 0] > run.tracked[19].covariance[0, 0]
    assert run.tracked[21].aligned


def test_a_bad_map_file_is_named_in_one_line(tmp_path):
    path = tmp_path / "m.json"
    path.write_text("{}")
    with pytest.raises(MapFileError, match="not a line map"):
        read_line_map(path)
    document = json.loads(room_map(tmp_path).read_text())
    document["lines"][2]["rho"] = "x"
    path.write_text(json.dumps(document))
    with pytest.raises(MapFileError, match=r"m.json: line 2: field rho: missing or not a number"):
        read_line_map(path)


def test_read_line_map_gives_the_lines_in_the_local_frame(tmp_path):
    lines, frame = read_line_map(room_map(tmp_path))
    assert isinstance(lines, LineSet)
    world = lines.start + np.array(frame.origin)
    n = np.column_stack((np.cos(lines.alpha), np.sin(lines.alpha)))
    rho = np.sum(n * (world - np.array(frame.origin)), axis=1)
    assert rho == pytest.approx(lines.rho, abs=0.05)


def test_localize_command_on_the_intel_excerpt(tmp_path):
    log = sample("intel")
    # The tracked map (--no-loops): with the loops closed the map is fused from the optimised
    # poses, and localised on it the scans stand a median 26 mm from them (2026-12-07).
    ran = scanlines("map", log, "--out", tmp_path / "m.json", "--align", "--no-loops",
                    "--poses-out", tmp_path / "mapped.tum")  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    mapped = load_trajectory(tmp_path / "mapped.tum")
    with open_log(log) as reader:
        first = [scan for _, scan in zip(range(6), reader, strict=False)][5]
    x, y, yaw = mapped.poses[np.searchsorted(mapped.times, first.timestamp)]
    ran = scanlines(
        "localize", log, "--map", tmp_path / "m.json",
        "--initial-pose", f"{first.timestamp},{x},{y},{yaw}", "--out", tmp_path / "p.tum",
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    assert "5 before time" in ran.stdout
    assert "odometry as learnt: heading drift" in ran.stdout
    poses = load_trajectory(tmp_path / "p.tum")
    assert len(poses.times) == 295
    covariances = json.loads((tmp_path / "p.cov.json").read_text())["records"]
    assert len(covariances) == 295
    # The map was made at the tracked poses: localised on it, the scans stand there again.
    i, j = match_times(poses.times, mapped.times)
    distance = np.linalg.norm(poses.poses[i, :2] - mapped.poses[j, :2], axis=1)
    assert np.median(distance) < 0.02
    # Along a corridor (about a third of the excerpt) the fit pins no shift along it and the
    # two runs part by up to half a metre before the corridor's end brings them together.
    assert np.mean(distance < 0.05) > 0.5
    assert np.max(distance) < 0.6
    # With --sides a return matches only a face the map saw from its side: still there.
    ran = scanlines(
        "localize", log, "--map", tmp_path / "m.json", "--sides",
        "--initial-pose", f"{first.timestamp},{x},{y},{yaw}", "--out", tmp_path / "s.tum",
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    sided = load_trajectory(tmp_path / "s.tum")
    i, j = match_times(sided.times, mapped.times)
    assert np.median(np.linalg.norm(sided.poses[i, :2] - mapped.poses[j, :2], axis=1)) < 0.02


def test_localize_errors_are_one_line(tmp_path):
    (tmp_path / "some.json").write_text("{}")
    ran = scanlines("localize", sample("intel"), "--map", tmp_path / "some.json",
                    "--initial-pose", "1,2,3", "--out", tmp_path / "p.tum")  # fmt: skip
    assert ran.returncode == 2
    assert "--initial-pose: '1,2,3' is not T,X,Y,YAW" in ran.stderr
    ran = scanlines("localize", sample("intel"), "--map", tmp_path / "none.json",
                    "--initial-pose", "1,2,3,0", "--out", tmp_path / "p.tum")  # fmt: skip
    assert ran.returncode == 2
    assert ran.stderr.strip().count("\n") == 0
    assert "none.json" in ran.stderr


@pytest.mark.parametrize("name", ["intel", "freiburg", "urg"])
def test_the_returns_localize_reads_are_the_scans_points(name):
    """localize's returns, bearings' cosines and sines kept from scan to scan: each scan's
    valid points, byte for byte."""
    from scanlines.map.localize import _Returns

    returns_of = _Returns()
    with open_log(sample(name)) as reader:
        scans = [scan for _, scan in reader.enumerate()]
    scans.append(Scan([1.0, np.nan, 2.0], -0.5, 0.5))  # other bearings
    for scan in scans:
        ours, theirs = returns_of(scan), scan.points[scan.valid].astype(np.float64)
        assert ours.tobytes() == theirs.tobytes()
        assert ours.shape == theirs.shape
