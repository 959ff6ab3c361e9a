"""Trajectory error (scanlines.evaluation.trajectory, ``scanlines eval --trajectory``): a
hand-computed case, evo's own figures where evo is installed, a log as the reference."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cli_helpers import scanlines
from scanlines.data import sample
from scanlines.evaluation.trajectory import (
    Trajectory,
    TrajectoryError,
    load_trajectory,
    match_times,
    trajectory_error,
)
from scanlines.map.poses import write_tum


def line(step: float, n: int = 6, t0: float = 0.0) -> Trajectory:
    """``n`` poses along x, ``step`` metres apart, one second apart, facing along x."""
    poses = np.array([(step * k, 0.0, 0.0) for k in range(n)])
    return Trajectory(t0 + np.arange(n, dtype=float), poses, f"line {step}")


def moved(trajectory: Trajectory, x: float, y: float, theta: float) -> Trajectory:
    c, s = math.cos(theta), math.sin(theta)
    p = trajectory.poses
    poses = np.column_stack(
        (x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1], p[:, 2] + theta)
    )
    return Trajectory(trajectory.times, poses, "moved")


def test_a_rigidly_moved_copy_scores_zero_and_the_motion_is_found():
    reference = line(1.0)
    score = trajectory_error(moved(reference, 3.0, -2.0, 2.0), reference)
    assert score.matched == 6
    assert score.ate_rmse == pytest.approx(0.0, abs=1e-9)
    assert score.rpe_rmse == pytest.approx(0.0, abs=1e-9)
    # The alignment undoes the motion: theta -2, and the origin's image maps back.
    assert score.alignment[2] == pytest.approx(-2.0)


def test_a_stretched_line_by_hand():
    """Steps of 1.1 m against 1 m: every 1 m pair of the reference is 0.1 m long in the
    estimate (RPE 0.1); after the best rigid fit the position errors are 0.1 (k - 2.5)."""
    score = trajectory_error(line(1.1), line(1.0))
    assert score.rpe_pairs == 5
    assert score.rpe_rmse == pytest.approx(0.1)
    assert score.ate_rmse == pytest.approx(0.1 * math.sqrt(17.5 / 6))
    assert score.ate_max == pytest.approx(0.25)
    assert score.path_length == pytest.approx(5.0)


def test_poses_match_only_within_10_ms():
    i, j = match_times(np.array([0.0, 1.0, 2.0]), np.array([0.009, 1.011, 1.995, 5.0]))
    assert i.tolist() == [0, 2]
    assert j.tolist() == [0, 2]
    with pytest.raises(TrajectoryError, match="1 of its 6 poses within 10 ms"):
        trajectory_error(line(1.0, t0=0.5), Trajectory(np.array([0.5]), np.zeros((1, 3)), "r"))


def test_a_clock_stepping_back_is_sorted_and_counted(tmp_path):
    path = tmp_path / "back.tum"
    write_tum(path, [(0.0, (0, 0, 0)), (2.0, (2, 0, 0)), (1.0, (1, 0, 0)), (3.0, (3, 0, 0))])
    loaded = load_trajectory(path)
    assert loaded.steps_back == 1
    assert loaded.times.tolist() == [0.0, 1.0, 2.0, 3.0]
    assert loaded.poses[:, 0].tolist() == [0.0, 1.0, 2.0, 3.0]


def test_the_figures_are_evo_s(tmp_path):
    evo_sync = pytest.importorskip("evo.core.sync")
    from evo.core import metrics
    from evo.tools import file_interface

    rng = np.random.default_rng(1)
    t = np.arange(0.0, 60.0, 0.1)
    truth = np.column_stack((5 * np.cos(t / 10), 3 * np.sin(t / 7), t / 10))
    noisy = moved(Trajectory(t, truth + rng.normal(0, 0.05, truth.shape), "e"), 1, -2, 0.7)
    write_tum(tmp_path / "ref.tum", list(zip(t, truth, strict=True)))
    write_tum(tmp_path / "est.tum", list(zip(t + 0.004, noisy.poses, strict=True)))
    score = trajectory_error(
        load_trajectory(tmp_path / "est.tum"), load_trajectory(tmp_path / "ref.tum")
    )
    ref = file_interface.read_tum_trajectory_file(str(tmp_path / "ref.tum"))
    est = file_interface.read_tum_trajectory_file(str(tmp_path / "est.tum"))
    ref, est = evo_sync.associate_trajectories(ref, est, max_diff=0.01)
    est.align(ref, correct_scale=False)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    assert score.ate_rmse == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse))
    assert score.ate_max == pytest.approx(ape.get_statistic(metrics.StatisticsType.max))
    rpe = metrics.RPE(
        metrics.PoseRelation.translation_part, 1.0, metrics.Unit.meters,
        pairs_from_reference=True,
    )  # fmt: skip
    rpe.process_data((ref, est))
    assert score.rpe_rmse == pytest.approx(rpe.get_statistic(metrics.StatisticsType.rmse))


def test_eval_trajectory_against_a_log_writes_strict_json(tmp_path):
    log = sample("intel")
    reference = load_trajectory(log)
    assert len(reference.times) > 10
    pairs = zip(reference.times, reference.poses, strict=True)
    stamped = [(t, (x + 0.01, y, a)) for t, (x, y, a) in pairs]
    write_tum(tmp_path / "est.tum", stamped)
    ran = scanlines(
        "eval", "trajectory", tmp_path / "est.tum", "--reference", log,
        "--out", tmp_path / "score.json",
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    assert "ATE RMSE" in ran.stdout
    score = json.loads((tmp_path / "score.json").read_text())
    assert score["ate_rmse"] == pytest.approx(0.0, abs=1e-5)
    assert score["matched"] == len(reference.times)


def test_eval_trajectory_errors_are_one_line(tmp_path):
    (tmp_path / "bad.tum").write_text("1 2 3\n")
    ran = scanlines("eval", "trajectory", tmp_path / "bad.tum", "--reference", sample("intel"))
    assert ran.returncode == 2
    assert ran.stderr.strip().count("\n") == 0
    assert "bad.tum: line 1: a TUM pose has 8 fields" in ran.stderr
    ran = scanlines("eval", "trajectory", tmp_path / "bad.tum")
    assert ran.returncode == 2
    assert ran.stderr.strip().count("\n") == 0
    assert "needs --reference" in ran.stderr
