"""Global localisation (scanlines.map.relocalise, ``localize`` without ``--initial-pose``): a
simulated room with asymmetric walls, found from no pose; a kidnapped robot declared lost and
found again; pose hypotheses from two segments on two map lines."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import scanlines
from scanlines import Scan
from scanlines.data import sample
from scanlines.evaluation.trajectory import load_trajectory, match_times
from scanlines.geometry.poses import compose, relative_pose
from scanlines.map import build_map
from scanlines.map.align import LineSet
from scanlines.map.export import write_map
from scanlines.map.localize import localize, read_line_map
from scanlines.map.relocalise import (
    ExplainedGrid,
    LineEnds,
    LinePairs,
    SearchSettings,
    end_candidates,
    pose_candidates,
)
from scanlines.map.scoring import beam_shares, first_hits, mapped
from test_map import view

#: A room with a shelf, a stub and a pillar: no turn or mirror of it looks the same.
WORLD = [((-4.0, -3.0), (4.0, -3.0)), ((4.0, -3.0), (4.0, 3.0)), ((4.0, 3.0), (-4.0, 3.0)),
         ((-4.0, 3.0), (-4.0, -3.0)), ((-4.0, 1.0), (-2.0, 1.0)), ((2.0, -3.0), (2.0, -1.5)),
         ((1.0, 2.0), (1.0, 3.0)), ((-1.0, -2.0), (-0.5, -2.0)),
         ((-0.5, -2.0), (-0.5, -1.5))]  # fmt: skip


def path(n: int):
    """True poses along the room, turning as they go."""
    return [(-3.0 + 6.0 * (k % 60) / 60, 0.3 * math.sin(k / 7), 0.5 * math.sin(k / 11))
            for k in range(n)]  # fmt: skip


def world_map(tmp_path):
    scans = [view(WORLD, pose, seed=k, sigma=0.003) for k, pose in enumerate(path(60))]
    out = tmp_path / "world.json"
    write_map(build_map(enumerate(scans)).line_map.lines(), out, overwrite=False)
    return read_line_map(out)


def drifting(truth, jump_at: int | None = None):
    """Scans of ``truth`` whose odometry drifts (0.2 deg a step, 2 % stretch); from
    ``jump_at`` on it also jumps 5 m along the heading and turns 90 deg."""
    odometry = [truth[0]]
    for k in range(1, len(truth)):
        step = relative_pose(truth[k - 1], truth[k])
        step = (1.02 * step[0], 1.02 * step[1], step[2] + math.radians(0.2))
        if k == jump_at:
            step = compose((5.0, 0.0, math.pi / 2), step)
        odometry.append(compose(odometry[-1], step))
    scans = []
    for k, (true, odo) in enumerate(zip(truth, odometry, strict=True)):
        seen = view(WORLD, true, seed=500 + k, sigma=0.003)
        scans.append(Scan(seen.ranges, seen.angle_min, seen.angle_increment, pose=odo,
                          timestamp=10.0 + 0.1 * k))  # fmt: skip
    return scans


def _error(run, frame, truth, record):
    pose = frame.world_pose(record.pose)
    true = truth[record.index]
    return math.hypot(pose[0] - true[0], pose[1] - true[1]), abs(
        math.remainder(pose[2] - true[2], 2 * math.pi)
    )


def test_pose_candidates_include_the_true_pose():
    from scanlines.extractor import Extractor

    lines, frame = _lines_only()
    true = (0.5, -0.2, 0.4)
    scan = view(WORLD, true, seed=3, sigma=0.002)
    rows = np.asarray(Extractor()(scan).lines)[:, :6]
    settings = SearchSettings()
    poses = pose_candidates(rows, lines, LinePairs(lines, settings), settings)
    local = frame.pose(true)
    distance = np.hypot(poses[:, 0] - local[0], poses[:, 1] - local[1])
    turn = np.abs(np.remainder(poses[:, 2] - local[2] + math.pi, 2 * math.pi) - math.pi)
    assert np.any((distance < 0.05) & (turn < math.radians(2.0)))


def _lines_only():
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        return world_map(Path(folder))


def test_without_an_initial_pose_the_pose_is_found_and_never_reported_wrong(tmp_path):
    lines, frame = world_map(tmp_path)
    truth = path(120)
    run = localize(enumerate(drifting(truth)), lines, frame, None)
    assert run.tracked[0].status == "lost"
    assert run.found_at
    assert run.found_at[0] < 60
    assert run.lost_at[0] == run.tracked[0].index  # one episode: lost until found
    assert len(run.lost_at) in (len(run.found_at), len(run.found_at) + 1)
    assert all(a < b for a, b in zip(run.lost_at, run.found_at, strict=False))
    for record in run.tracked:
        if record.status != "lost":
            distance, turn = _error(run, frame, truth, record)
            assert distance < 0.1, record.index
            assert turn < math.radians(3.0), record.index
    assert run.tracked[-1].status != "lost"


def test_a_kidnapped_robot_is_declared_lost_then_found_again(tmp_path):
    lines, frame = world_map(tmp_path)
    truth = path(160)
    start = (10.0, truth[0])
    run = localize(enumerate(drifting(truth, jump_at=60)), lines, frame, start)
    assert all(record.status != "lost" for record in run.tracked[:60])
    assert run.lost_at
    assert 60 <= run.lost_at[0] < 80
    assert run.found_at
    assert run.lost_at[0] < run.found_at[-1] < 160
    found = run.found_at[-1]
    for record in run.tracked[found:]:
        distance, turn = _error(run, frame, truth, record)
        assert distance < 0.1, record.index
        assert turn < math.radians(3.0), record.index


def test_localize_without_an_initial_pose_says_lost_and_found(tmp_path):
    log = sample("intel")
    ran = scanlines("map", log, "--out", tmp_path / "m.json", "--align",
                    "--poses-out", tmp_path / "mapped.tum")  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    out = tmp_path / "p.tum"
    ran = scanlines("localize", log, "--map", tmp_path / "m.json", "--out", out)
    assert ran.returncode == 0, ran.stderr
    assert "scans lost" in ran.stderr
    assert "found at" in ran.stderr
    document = json.loads(out.with_name("p.cov.json").read_text())
    statuses = [r["status"] for r in document["records"]]
    assert statuses[0] == "lost"
    assert "found" in statuses
    assert document["at_the_end"] == "found"
    # where found, the scans stand where the map was made
    poses, mapped = load_trajectory(out), load_trajectory(tmp_path / "mapped.tum")
    i, j = match_times(poses.times, mapped.times)
    found = np.array([s != "lost" for s in statuses])[i]
    distance = np.linalg.norm(poses.poses[i, :2] - mapped.poses[j, :2], axis=1)
    assert found.sum() > 100
    assert np.median(distance[found]) < 0.05


#: A corridor between two walls, a doorway in one of them and a wall behind: every wall
#: parallel, only the doorway's jambs fix a position along the corridor.
CORRIDOR = [((-10.0, -1.0), (10.0, -1.0)), ((-10.0, 1.0), (2.0, 1.0)),
            ((3.0, 1.0), (10.0, 1.0)), ((-10.0, 3.0), (10.0, 3.0))]  # fmt: skip


def _line_set(walls) -> LineSet:
    start, end = np.array([a for a, _ in walls]), np.array([b for _, b in walls])
    alpha = np.arctan2(end[:, 0] - start[:, 0], -(end[:, 1] - start[:, 1]))
    rho = np.cos(alpha) * start[:, 0] + np.sin(alpha) * start[:, 1]
    alpha = np.where(rho < 0, alpha + math.pi, alpha)
    return LineSet(np.abs(rho), np.remainder(alpha + math.pi, 2 * math.pi) - math.pi, start, end)


@pytest.mark.parametrize("true", [(0.5, -0.2, 0.3), (4.2, 0.1, 2.9), (1.0, 0.3, -0.2)])
def test_a_doorway_in_a_corridor_fixes_the_pose_that_parallel_walls_cannot(true):
    from scanlines.extractor import Extractor

    lines = _line_set(CORRIDOR)
    settings = SearchSettings()
    extraction = Extractor()(view(CORRIDOR, true, seed=5, sigma=0.002))
    rows, kinds = np.asarray(extraction.lines)[:, :6], np.asarray(extraction.end_kinds)
    assert len(pose_candidates(rows, lines, LinePairs(lines, settings), settings)) == 0
    poses = end_candidates(rows, kinds, lines, LineEnds(lines, settings), settings)
    distance = np.hypot(poses[:, 0] - true[0], poses[:, 1] - true[1])
    turn = np.abs(np.remainder(poses[:, 2] - true[2] + math.pi, 2 * math.pi) - math.pi)
    assert np.any((distance < 0.05) & (turn < math.radians(2.0)))


def test_only_the_ends_of_walls_are_open_ends():
    lines = _line_set([*CORRIDOR, ((10.0, -1.0), (10.0, 3.0))])
    ends = LineEnds(lines, SearchSettings())
    jambs = np.isin(np.round(ends.point[:, 0], 6), (2.0, 3.0)) & (ends.point[:, 1] == 1.0)
    assert jambs.any()
    assert ends.open[jambs].all()
    corners = ends.point[:, 0] == 10.0
    assert corners.any()
    assert not ends.open[corners].any()


@pytest.mark.parametrize("count", [0, 1])
def test_a_map_too_small_to_fix_a_pose_gives_no_candidate(count):
    from scanlines.map.align import LineSet

    lines = LineSet(np.ones(count), np.zeros(count), np.zeros((count, 2)),
                    np.column_stack((np.zeros(count), np.ones(count))))  # fmt: skip
    settings = SearchSettings()
    rows = np.array([[1.0, 0.0, 1.0, -1.0, 1.0, 1.0], [1.0, math.pi / 2, -1.0, 1.0, 1.0, 1.0]])
    assert len(pose_candidates(rows, lines, LinePairs(lines, settings), settings)) == 0


@settings(max_examples=60, deadline=None)
@given(
    st.tuples(st.floats(-12, 12), st.floats(-12, 12), st.floats(-7, 7)),
    st.integers(0, 2**32 - 1),
)
def test_the_share_at_one_pose_is_the_share_of_the_many_pose_form(pose, seed):
    rng = np.random.default_rng(seed)
    start, end = rng.uniform(-8, 8, (12, 2)), rng.uniform(-8, 8, (12, 2))
    grid = ExplainedGrid(start, end, 0.05, 0.05)
    points = rng.uniform(-10, 10, (int(rng.integers(1, 300)), 2))
    assert grid.share_at(points, pose) == float(grid.shares(points, np.asarray(pose))[0])
    assert grid.share_at(points[:0], pose) == 0.0


def test_beams_cast_on_the_map_tell_walls_seen_through_from_places_the_map_lacks():
    # a wall at x = 2 (y -1..1); the sensor at the origin facing +x
    lines = LineSet(np.zeros(1), np.zeros(1), np.array([[2.0, -1.0]]), np.array([[2.0, 1.0]]))
    points = np.array([[2.0, 0.0], [3.0, 0.0], [1.0, 0.2], [0.0, 4.0]])
    hits = first_hits(points, np.zeros(3), lines.start, lines.end, 10.0)[0]
    assert hits[:2] == pytest.approx([2.0, 2.0])
    assert hits[3] == math.inf
    explained = np.array([True, False, False, False])
    through, short = beam_shares(points, (0.0, 0.0, 0.0), explained, lines, 0.3, 10.0)
    assert (through, short) == (0.25, 0.25)  # one beyond the wall, one in front; one unmapped
    settings = SearchSettings()
    count = settings.agree_far
    assert mapped([0.4] * count, [(0.0, 0.1)] * count, count, settings)
    assert not mapped([0.4] * count, [(0.05, 0.0)] * count, count, settings)  # through walls
    assert not mapped([0.4] * count, [(0.0, 0.3)] * count, count, settings)  # 0.4 of 0.7
    assert not mapped([0.3] * count, [(0.0, 0.0)] * count, count, settings)  # too little
    assert not mapped([0.9] * (count - 1), [(0.0, 0.0)] * (count - 1), count, settings)
