"""Mapping with tracking (scanlines.map.tracking, ``scanlines map --align``): a simulated
log whose odometry drifts is tracked back onto the true path, a scan that does not fit is
kept out of the map, and the poses are written as TUM with their covariances."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cli_helpers import scanlines
from scanlines import Scan
from scanlines.data import sample
from scanlines.evaluation.trajectory import Trajectory, load_trajectory, trajectory_error
from scanlines.geometry.poses import compose, relative_pose
from scanlines.map import build_map
from scanlines.map.tracking import TrackSettings, tracking_summary
from test_map import view
from test_map_align import ROOM

CORRIDOR = [((-4.0, -1.0), (12.0, -1.0)), ((-4.0, 1.0), (12.0, 1.0)), ((-4.0, -1.0), (-4.0, 1.0))]


def drifting_log(n: int = 80, walls=ROOM):
    """Scans of ``walls`` along a path; each carries odometry that drifts (a turn bias of
    0.3 deg and a 3 % stretch per step), the true poses returned beside them."""
    truth = [(-2.0 + 4.0 * k / n, 0.8 * math.sin(k / 12), 0.4 * math.sin(k / 15)) for k in range(n)]
    odometry = [truth[0]]
    for k in range(1, n):
        step = relative_pose(truth[k - 1], truth[k])
        step = (1.03 * step[0], 1.03 * step[1], step[2] + math.radians(0.3))
        odometry.append(compose(odometry[-1], step))
    scans = []
    for k, (true, odo) in enumerate(zip(truth, odometry, strict=True)):
        scan = view(walls, true, seed=k, sigma=0.003)
        scans.append(Scan(scan.ranges, scan.angle_min, scan.angle_increment, pose=odo,
                          timestamp=100.0 + 0.1 * k))  # fmt: skip
    return scans, np.array(truth)


def _errors(build, truth):
    frame = build.frame
    tracked = np.array([frame.world_pose(t.pose) for t in build.tracked])
    odometry = np.array([frame.world_pose(t.odometry) for t in build.tracked])
    return (np.linalg.norm(tracked[:, :2] - truth[:, :2], axis=1),
            np.linalg.norm(odometry[:, :2] - truth[:, :2], axis=1))  # fmt: skip


def test_tracking_pulls_drifting_odometry_back_onto_the_true_path():
    scans, truth = drifting_log()
    build = build_map(enumerate(scans), track=TrackSettings())
    tracked, odometry = _errors(build, truth)
    assert odometry.max() > 0.3  # the odometry drifts well away
    assert tracked.max() < 0.03
    assert build.aligned + build.unaligned_first == len(scans)
    assert build.not_aligned == 0
    summary = tracking_summary(build.tracked, build.frame)
    assert summary["aligned"] == build.aligned
    assert summary["from_source_m"]["max"] == pytest.approx(odometry.max(), abs=0.03)
    assert 0 < summary["sigma_m"]["median"] < 0.01


def test_a_corridor_pins_no_shift_along_it_and_odometry_holds_it():
    """Along a corridor the fit is free; the prior keeps the odometry's increment there,
    and the covariance says the pose is known less well along it than across."""
    truth = [(0.5 * k, 0.0, 0.0) for k in range(12)]
    scans = [Scan(*_ranges(view(CORRIDOR, pose, seed=k, sigma=0.003)), pose=pose) for k, pose
             in enumerate(truth)]  # fmt: skip
    build = build_map(enumerate(scans), track=TrackSettings())
    last = build.tracked[-1]
    assert last.aligned
    assert last.covariance[0, 0] > 10 * last.covariance[1, 1]
    assert build.frame.world_pose(last.pose)[1] == pytest.approx(0.0, abs=0.01)


def _ranges(scan: Scan):
    return scan.ranges, scan.angle_min, scan.angle_increment


def test_a_scan_that_does_not_fit_is_kept_out_of_the_map():
    scans, _ = drifting_log(40)
    elsewhere = [((-1.0, -1.0), (1.0, -1.0)), ((1.0, -1.0), (1.0, 1.0))]  # a box, not the room
    odd = view(elsewhere, (0.0, 0.0, 0.0), seed=99, sigma=0.003)
    scans[30] = Scan(odd.ranges, odd.angle_min, odd.angle_increment, pose=scans[30].pose)
    build = build_map(enumerate(scans), track=TrackSettings())
    assert build.not_aligned == 1
    assert build.tracked[30].status == "did not fit"
    assert build.scans == len(scans) - 1
    assert build.line_map.lines(min_scans=1).last_scan.max() == len(scans) - 1


def test_map_align_writes_tum_poses_and_covariances(tmp_path):
    log = sample("intel")
    ran = scanlines(
        "map", log, "--out", tmp_path / "m.json", "--align", "--poses-out", tmp_path / "p.tum"
    )
    assert ran.returncode == 0, ran.stderr
    assert "tracked:" in ran.stdout
    assert "alignment moved each pose" in ran.stdout
    poses = load_trajectory(tmp_path / "p.tum")
    records = json.loads((tmp_path / "p.cov.json").read_text())["records"]
    assert len(records) == len(poses.times) == 300
    assert np.array(records[-1]["covariance"]).reshape(3, 3)[0, 0] > 0
    meta = json.loads((tmp_path / "m.json").read_text())["tracking"]
    assert meta["aligned"] + meta["first_unaligned"] + meta["not_aligned"] == 300
    # The tracked poses are consistent with the log's odometry over short spans.
    score = trajectory_error(poses, load_trajectory(log))
    assert score.rpe_rmse is not None
    assert score.rpe_rmse < 0.2


def test_poses_out_needs_align(tmp_path):
    ran = scanlines(
        "map", sample("intel"), "--out", tmp_path / "m.json", "--poses-out", tmp_path / "p.tum"
    )
    assert ran.returncode == 2
    assert "--poses-out writes the tracked poses; it needs --align" in ran.stderr


def test_tracked_poses_score_against_their_truth():
    scans, truth = drifting_log()
    build = build_map(enumerate(scans), track=TrackSettings())
    times = np.array([t.timestamp for t in build.tracked])
    estimate = Trajectory(times, np.array([t.pose for t in build.tracked]), "tracked")
    odometry = Trajectory(times, np.array([t.odometry for t in build.tracked]), "odometry")
    reference = Trajectory(times, truth - [*build.frame.origin, 0.0], "truth")
    assert trajectory_error(estimate, reference).ate_rmse < 0.2 * (
        trajectory_error(odometry, reference).ate_rmse
    )
