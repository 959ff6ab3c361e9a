"""Scan-to-scan repeatability (``scanlines eval --real``) and the ICP it registers with."""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import Ran, scanlines
from scanlines import Scan
from scanlines.evaluation.repeatability import (
    RepeatTolerances,
    candidate_pairs,
    match_segments,
    register_pairs,
    repeatability_of_scans,
    view_overlap,
)
from scanlines.geometry.registration import (
    compose,
    icp,
    invert,
    line_target,
    relative_pose,
    transform_points,
)
from scanlines.sim import get_sensor, random_scene, simulate

DATA = Path(__file__).parents[1] / "src" / "scanlines" / "data"
PERTURBATION = (0.07, -0.07, math.radians(3.0))  # 9.9 cm and 3 deg off the true motion


def without_bias(sensor: str):
    """The preset's noise without its per-scan range bias.

    A range bias drawn anew for every scan is not a rigid motion: two scans with
    different biases have no exact relative pose to recover (with the LMS bias of
    +-1.5 cm the best fit is off by up to 2.5 cm, with the TiM571's +-6 cm by up to 12 cm).
    """
    return dataclasses.replace(get_sensor(sensor).noise, bias=0.0, bias_rel=0.0)


def moved(pose, forward: float, turn_deg: float):
    x, y, t = pose
    return (x + forward * math.cos(t), y + forward * math.sin(t), t + math.radians(turn_deg))


def errors(pose, true) -> tuple[float, float]:
    return (
        math.hypot(pose[0] - true[0], pose[1] - true[1]),
        abs(math.degrees(math.remainder(pose[2] - true[2], 2 * math.pi))),
    )


def test_poses_compose_and_invert():
    a, b = (1.0, 2.0, 0.5), (-0.3, 0.4, -1.2)
    assert np.allclose(compose(a, invert(a)), (0, 0, 0), atol=1e-12)
    points = np.array([[1.0, 0.0], [0.5, -2.0]])
    assert np.allclose(
        transform_points(transform_points(points, b), a), transform_points(points, compose(a, b))
    )
    assert np.allclose(compose(a, relative_pose(a, b)), b)


@pytest.mark.parametrize("sensor", ["lms_05deg", "urg04lx"])
@pytest.mark.parametrize("seed", range(4))
def test_icp_recovers_known_motion_on_simulated_pairs(sensor, seed):
    scene = random_scene(seed, sensor, kind="room")
    second = moved(scene.pose, 0.1 + 0.05 * seed, (-1) ** seed * (2.0 + seed))
    noise = without_bias(sensor)
    a = simulate(scene.world, sensor, scene.pose, seed=seed, noise=noise).scan
    b = simulate(scene.world, sensor, second, seed=seed + 100, noise=noise).scan
    true = relative_pose(a.pose, b.pose)
    fit = icp(b.points[b.valid], line_target(a), compose(true, PERTURBATION))
    translation, rotation = errors(fit.pose, true)
    assert translation <= 0.02
    assert rotation <= 0.5
    assert fit.converged
    assert fit.inlier_fraction > 0.6
    assert fit.rms < 0.03


def test_icp_alone_registers_a_log_without_poses():
    sensor = "lms_05deg"
    scene = random_scene(3, sensor, kind="room")
    poses = [scene.pose]
    for _ in range(4):
        poses.append(moved(poses[-1], 0.08, 1.5))
    noise = without_bias(sensor)
    sims = [simulate(scene.world, sensor, p, seed=k, noise=noise).scan for k, p in enumerate(poses)]
    bare = [
        (k, Scan(s.ranges, s.angle_min, s.angle_increment, s.range_min, s.range_max))
        for k, s in enumerate(sims)
    ]
    pairs, source = register_pairs(bare)
    assert source == "ICP alone"
    assert [(p.i, p.j) for p in pairs] == [
        (i, j) for i in range(4) for j in range(i + 1, 5) if j - i <= 3
    ]
    for pair in pairs:
        translation, rotation = errors(pair.pose, relative_pose(poses[pair.i], poses[pair.j]))
        assert translation <= 0.02, pair
        assert rotation <= 0.5, pair
        assert pair.used


def segment(start, end):
    return [*start, *end]


@pytest.mark.parametrize(
    ("other", "matches"),
    [
        (segment((0, 0), (2, 0)), True),  # itself
        (segment((2, 0), (0, 0)), True),  # reversed
        (segment((0.5, 0.025), (3.0, 0.025)), True),  # 2.5 cm off, overlapping 1.5 of 2.5 m
        (segment((0.5, 0.035), (3.0, 0.035)), False),  # 3.5 cm off
        (segment((1.0, 0.0), (1.0 + 2 * math.cos(0.03), 2 * math.sin(0.03))), True),  # 1.7 deg
        (segment((1.0, 0.0), (1.0 + 2 * math.cos(0.04), 2 * math.sin(0.04))), False),  # 2.3 deg
        (segment((1.1, 0.0), (3.0, 0.0)), False),  # overlap 0.9 of the shorter 1.9 m: 0.47
        (segment((0.9, 0.0), (3.0, 0.0)), True),  # overlap 1.1 of 2.1 m: 0.52
        (segment((1.6, 0.0), (2.4, 0.0)), True),  # overlap 0.4 of the shorter 0.8 m: 0.5
        (segment((2.1, 0.0), (3.0, 0.0)), False),  # beside it, on its line
    ],
)
def test_segment_match_tolerances(other, matches):
    mine = np.array([segment((0, 0), (2, 0))])
    assert bool(match_segments(mine, np.array([other]))[0, 0]) is matches


def test_the_distance_is_taken_where_the_segments_overlap():
    # Tilted by 1.5 deg about x = 10 m: far from the origin of i's frame (|drho| 26 cm in
    # Hesse form), but within 3 cm over the 1 m they share.
    tilt = math.radians(1.5)
    other = np.array([segment((9.5, -0.5 * math.sin(tilt)), (10.5, 0.5 * math.sin(tilt)))])
    mine = np.array([segment((9.0, 0.0), (10.5, 0.0))])
    assert match_segments(mine, other)[0, 0]
    assert not match_segments(mine, other, RepeatTolerances(distance_at="origin"))[0, 0]


def test_view_overlap_of_a_scan_with_itself_and_turned_away():
    scan = random_scene(1, "lms_05deg", kind="room").scan(seed=1).scan
    assert view_overlap(scan, scan, (0.0, 0.0, 0.0)) == pytest.approx(1.0)
    assert view_overlap(scan, scan, (0.0, 0.0, math.pi)) < 0.05


def copies(scan: Scan, n: int, offset=(0.0, 0.0, 0.0)) -> list[tuple[int, Scan]]:
    """``n`` exact copies of ``scan``, the log pose of each moved by ``offset`` more."""
    pose = scan.pose
    out = []
    for k in range(n):
        beams = (scan.ranges, scan.angle_min, scan.angle_increment)
        out.append((k, Scan(*beams, scan.range_min, scan.range_max, pose=pose)))
        pose = compose(pose, offset)
    return out


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (0.06, -0.05, math.radians(2.0))])
def test_exact_copies_repeat_fully(offset):
    # The copies see the same world from the same place; with the offset the log's poses
    # say they moved, and ICP must take that motion back out.
    scan = random_scene(2, "lms_05deg", kind="room").scan(seed=2).scan
    result = repeatability_of_scans(copies(scan, 5, offset), ["adaptive", "iepf"])
    assert len(result.used_pairs) == len(result.pairs) == 9
    for pair in result.pairs:
        translation, rotation = errors(pair.pose, (0.0, 0.0, 0.0))
        assert translation < 0.005
        assert rotation < 0.05
    for method in result.methods:
        assert method.long_segments > 0
        assert method.repeatability == 1.0
        assert method.per_pair == 1.0
        assert 0.5 < method.coverage <= 1.0
        assert method.per_scan == method.segments / 5
        assert method.strict == 1.0
        assert method.strict_pairs == 9
        assert method.repeated_metres > 0.5


def test_stricter_distance_tolerance_repeats_less():
    scene = random_scene(4, "lms_05deg", kind="room")
    scans = [
        (k, scene.scan(seed=k).scan) for k in range(4)
    ]  # one place, noise drawn anew: the segments move by the noise alone
    loose = repeatability_of_scans(scans, ["iepf"]).methods[0]
    strict_tol = RepeatTolerances(distance=0.002)
    strict = repeatability_of_scans(scans, ["iepf"], tol=strict_tol).methods[0]
    assert loose.long_segments == strict.long_segments > 0
    assert strict.repeatability < loose.repeatability


def test_strict_measure_weighs_length_and_compares_rho_at_the_origin():
    scene = random_scene(4, "lms_05deg", kind="room")
    scans = [(k, scene.scan(seed=k).scan) for k in range(4)]
    loose = repeatability_of_scans(scans, ["iepf"]).methods[0]
    tight = RepeatTolerances(strict_distance=0.002)
    strict = repeatability_of_scans(scans, ["iepf"], tol=tight).methods[0]
    assert loose.strict_pairs == strict.strict_pairs == 6
    assert strict.strict < loose.strict <= 1.0
    assert strict.repeated_metres < loose.repeated_metres
    assert strict.repeatability == loose.repeatability  # the lenient measure is untouched


def test_max_pairs_spreads_the_pairs_over_the_log():
    scene = random_scene(1, "lms_1deg", kind="room")
    scans = [(k, scene.scan(seed=0).scan) for k in range(300)]
    pairs, _ = register_pairs(scans, RepeatTolerances(max_pairs=50))
    chosen = [(p.i, p.j) for p in pairs]
    assert len(chosen) == len(set(chosen)) == 50  # every one used: one tried per slot
    assert all(p.used for p in pairs)
    assert all(1 <= b - a <= 3 for a, b in chosen)
    starts = [a for a, _ in chosen]
    assert starts == sorted(starts)
    assert starts[0] == 0
    assert starts[-1] >= 290
    assert {b - a for a, b in chosen} == {1, 2, 3}
    assert len(candidate_pairs(scans, RepeatTolerances())) == 299 + 298 + 297


def run(*args: str, cwd: Path) -> Ran:
    return scanlines(*args, cwd=cwd)


SUMMARY_COLUMNS = {
    "log",
    "scans",
    "pose_source",
    "label",
    "spec",
    "segments",
    "long_segments",
    "repeated",
    "repeatability",
    "per_pair",
    "coverage",
    "median_length",
    "short_share",
    "per_scan",
    "per_metre",
    "pairs_used",
    "strict",
    "repeated_metres",
    "strict_pairs",
    "mode",
    "fidelity_mm",
    "fidelity_segments",
}


def test_eval_real_command_on_the_shipped_excerpts(tmp_path):
    logs = [DATA / "fr079_excerpt.log.gz", DATA / "intel_excerpt.clf.gz"]
    args = ["eval", "--scans", "20", "-m", "adaptive", "-m", "iepf", "--out", "out"]
    out = run(*args, *(a for log in logs for a in ("--real", str(log))), cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "repeat." in out.stdout
    assert "coverage" in out.stdout
    assert out.stdout.count("log poses + ICP") == 2
    with (tmp_path / "out" / "repeatability.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert set(rows[0]) >= SUMMARY_COLUMNS
    assert [(Path(r["log"]).name, r["label"]) for r in rows] == [
        (log.name, label) for log in logs for label in ("adaptive", "iepf")
    ]
    for row in rows:
        assert row["scans"] == "20"
        assert int(row["pairs_used"]) > 40  # of 3 * 20 - 6 = 54 candidates
        for name in ("repeatability", "per_pair", "coverage", "short_share"):
            assert 0.0 <= float(row[name]) <= 1.0, (name, row)
        assert float(row["repeatability"]) > 0.5
    with (tmp_path / "out" / "repeatability_pairs.csv").open() as handle:
        pairs = list(csv.DictReader(handle))
    assert len(pairs) == 2 * 54
    assert (tmp_path / "out" / "repeatability.json").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--seed", "0"], "--seed"),
        (["-m", "truth"], "truth"),
        (["--tol-rho", "0.1", "--tol-beams", "3"], "--tol-rho"),
    ],
)
def test_eval_real_refuses_options_of_simulated_scenes(args, message, tmp_path):
    log = str(DATA / "fr079_excerpt.log.gz")
    out = run("eval", "real", log, *args, cwd=tmp_path)
    assert out.returncode == 2
    assert message in out.stderr


def test_scans_is_not_an_option_of_simulated_scenes(tmp_path):
    out = run("eval", "sim", "--scans", "5", cwd=tmp_path)
    assert out.returncode == 2
    assert "--scans" in out.stderr
