"""The localisation filter (scanlines.map.filter and its compiled kernel): the grid of map
lines finds every line a return can meet, the filter learns the odometry's drift, scale and
the sensor's lever on simulated logs, refuses a wall that runs another way, and localize
starts at the scan of the initial time even where the clock steps back."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scanlines import Scan
from scanlines.geometry.poses import compose, relative_pose
from scanlines.map.align import LineSet, nearest_segments
from scanlines.map.filter import FilterSettings, LineMapFilter, line_grid
from scanlines.map.frame import LocalFrame
from scanlines.map.localize import localize
from test_map import view
from test_map_align import ROOM, room_lines

coordinate = st.floats(-20.0, 20.0, allow_nan=False)
segment = st.tuples(coordinate, coordinate, coordinate, coordinate)


@settings(max_examples=60, deadline=None)
@given(st.lists(segment, min_size=1, max_size=12), st.lists(st.tuples(coordinate, coordinate),
       min_size=1, max_size=30), st.floats(0.05, 1.5), st.floats(0.1, 2.0))  # fmt: skip
def test_the_grid_lists_every_line_within_reach_of_a_point(walls, points, reach, cell):
    start = np.array([w[:2] for w in walls])
    end = np.array([w[2:] for w in walls])
    lines = LineSet(np.zeros(len(walls)), np.zeros(len(walls)), start, end)
    grid = line_grid(lines, reach, cell)
    assert grid.cell_start[0] == 0
    assert grid.cell_start[-1] == len(grid.cell_lines)
    assert np.all(np.diff(grid.cell_start) >= 0)
    for point in points:
        p = np.array([point])
        within = [
            k
            for k in range(len(walls))
            if nearest_segments(p, start[k : k + 1], end[k : k + 1])[0][0] <= reach
        ]
        assert set(within) <= set(grid.candidates(point).tolist())


def test_a_point_at_exactly_the_reach_of_a_line_finds_it():
    # Found by the test above: a point just below the grid's edge, 1 m from a point-like line.
    lines = LineSet(np.zeros(1), np.zeros(1), np.array([[0.0, 1.0]]), np.array([[0.0, 1.0]]))
    grid = line_grid(lines, 1.0, 1.0)
    assert grid.candidates((0.0, -2.13e-175)).tolist() == [0]
    assert grid.candidates((1.0, 1.0)).tolist() == [0]


def test_the_grid_of_no_lines_has_no_candidates():
    empty = LineSet(np.zeros(0), np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)))
    grid = line_grid(empty, 0.5)
    assert len(grid.candidates((0.0, 0.0))) == 0


def _circle(n: int, radius: float = 1.2, centre=(-1.5, 0.5)):
    """Poses along a circle inside ROOM, heading along it (about 5 cm apart)."""
    poses = []
    for k in range(n):
        a = 0.045 * k / radius
        poses.append((centre[0] + radius * math.cos(a), centre[1] + radius * math.sin(a),
                      math.remainder(a + math.pi / 2, 2 * math.pi)))  # fmt: skip
    return poses


def _stadium(n: int, radius: float = 1.2, left: float = -2.5, right: float = -0.3):
    """Poses round a stadium inside ROOM (two straights, two half circles: on a circle
    alone, a lever across the robot and a scale error move it alike), 4.5 cm apart."""
    straight, half = right - left, math.pi * radius
    lap = 2 * (straight + half)
    poses = []
    for k in range(n):
        s = (0.045 * k) % lap
        if s < straight:  # along the bottom, heading +x
            poses.append((left + s, 0.5 - radius, 0.0))
        elif s < straight + half:  # the right half circle
            a = -math.pi / 2 + (s - straight) / radius
            poses.append((right + radius * math.cos(a), 0.5 + radius * math.sin(a),
                          math.remainder(a + math.pi / 2, 2 * math.pi)))  # fmt: skip
        elif s < 2 * straight + half:  # along the top, heading -x
            poses.append((right - (s - straight - half), 0.5 + radius, math.pi))
        else:  # the left half circle
            a = math.pi / 2 + (s - 2 * straight - half) / radius
            poses.append((left + radius * math.cos(a), 0.5 + radius * math.sin(a),
                          math.remainder(a + math.pi / 2, 2 * math.pi)))  # fmt: skip
    return poses


def _odometry(truth, scale=1.0, drift=0.0, lever=(0.0, 0.0)):
    """Odometry of the robot whose sensor follows ``truth``: the sensor sits at ``lever`` on
    the robot; each step's distance is ``scale`` times too long and its turn ``drift``
    radians per metre too small."""
    offset = (lever[0], lever[1], 0.0)
    inverse = relative_pose(offset, (0.0, 0.0, 0.0))
    robot = [compose(pose, inverse) for pose in truth]
    odometry = [robot[0]]
    for a, b in itertools.pairwise(robot):
        step = relative_pose(a, b)
        d = math.hypot(step[0], step[1])
        odometry.append(compose(odometry[-1], (scale * step[0], scale * step[1],
                                               step[2] - drift * d)))  # fmt: skip
    return odometry


def _run(truth, odometry, filter_settings=None, seed=0):
    tracker = LineMapFilter(room_lines(ROOM), filter_settings)
    tracker.start(truth[0], (0.01, math.radians(0.5)))
    poses, steps = [], []
    for k, (true, odo) in enumerate(zip(truth, odometry, strict=True)):
        scan = view(ROOM, true, seed=seed + k, sigma=0.003)
        increment = None if k == 0 else relative_pose(odometry[k - 1], odo)
        step = tracker.step(scan.points[scan.valid], increment)
        steps.append(step)
        poses.append(step.pose)
    error = np.linalg.norm(np.array(poses)[:, :2] - np.array(truth)[:, :2], axis=1)
    return tracker, error, steps


def test_the_filter_learns_the_odometrys_drift_and_scale():
    truth = _stadium(600)
    odometry = _odometry(truth, scale=1.04, drift=0.05)
    tracker, error, steps = _run(truth, odometry)
    assert all(step.aligned for step in steps)
    assert error.max() < 0.02
    # The state's drift and scale correct the odometry's: 0.05 * (1 / 1.04) rad per metre of
    # odometry, 1 / 1.04 - 1 of its distance.
    assert tracker.state[3] == pytest.approx(0.05 / 1.04, abs=0.008)
    assert tracker.state[4] == pytest.approx(1 / 1.04 - 1, abs=0.008)


def test_dead_reckoning_on_the_learnt_odometry_beats_the_raw_one():
    truth = _stadium(400)
    odometry = _odometry(truth, scale=1.04, drift=0.05)
    tracker, _, _ = _run(truth[:300], odometry[:300])
    learnt = frozen = tuple(truth[299])
    # Past the map: the odometry's increments alone, corrected by the learnt state or not.
    drift, scale = tracker.state[3], tracker.state[4]
    for a, b in itertools.pairwise(odometry[299:]):
        step = relative_pose(a, b)
        d = math.hypot(step[0], step[1])
        learnt = compose(learnt, ((1 + scale) * step[0], (1 + scale) * step[1],
                                  step[2] + drift * d))  # fmt: skip
        frozen = compose(frozen, step)
    end = np.array(truth[-1][:2])
    assert np.linalg.norm(np.array(learnt[:2]) - end) < 0.25 * np.linalg.norm(
        np.array(frozen[:2]) - end
    )


def test_the_filter_learns_where_the_sensor_sits_on_a_robot_turning_in_place():
    lever = (0.25, 0.05)
    robot = [(-1.0, 0.5, math.remainder(0.06 * k, 2 * math.pi)) for k in range(300)]
    truth = [compose(pose, (*lever, 0.0)) for pose in robot]  # the sensor circles
    odometry = _odometry(truth, lever=lever)
    tracker, error, _ = _run(truth, odometry)
    assert tracker.state[5:7] == pytest.approx(lever, abs=0.02)
    assert np.median(error[100:]) < 0.01
    # Not learnt (a lever held at zero), the sensor's circle is missed.
    frozen = FilterSettings(lever_sigma=1e-9)
    _, held, _ = _run(truth, odometry, frozen)
    assert np.median(held[100:]) > 2 * np.median(error[100:])


@pytest.mark.parametrize(("turn_deg", "fits"), [(5.0, True), (45.0, False), (90.0, False)])
def test_a_wall_that_runs_another_way_is_not_matched(turn_deg, fits):
    wall = [((-3.0, 1.0), (3.0, 1.0))]
    tracker = LineMapFilter(room_lines(wall))
    tracker.start((0.0, 0.0, 0.0), (0.3, math.radians(1.0)))
    # The scan's wall crosses the map's at the robot's left, turned by turn_deg.
    a = math.radians(turn_deg)
    seen = [((-3.0 * math.cos(a), 1.0 - 3.0 * math.sin(a)), (3.0 * math.cos(a),
             1.0 + 3.0 * math.sin(a)))]  # fmt: skip
    scan = view(seen, (0.0, 0.0, 0.0), seed=3, sigma=0.002)
    step = tracker.step(scan.points[scan.valid], None)
    assert step.aligned is fits
    if not fits:
        assert step.status == "too few returns on map lines"
        assert step.pose == pytest.approx((0.0, 0.0, 0.0))


def test_a_far_correction_is_refused_as_inconsistent():
    walls = [((-3.0, 1.0), (3.0, 1.0)), ((2.0, -3.0), (2.0, 3.0))]
    strict = FilterSettings(max_chi_square=4.0, gate_min=0.5, gate_max=0.5)
    tracker = LineMapFilter(room_lines(walls), strict)
    tracker.start((0.0, 0.0, 0.0), (0.05, math.radians(0.5)))
    scan = view(walls, (0.3, 0.3, 0.0), seed=4, sigma=0.002)  # 6 sigma away
    step = tracker.step(scan.points[scan.valid], None)
    assert step.status == "inconsistent with the prediction"
    assert step.pose == pytest.approx((0.0, 0.0, 0.0))
    assert step.chi_square > 4.0


def _clutter(seed: int, count: int) -> list:
    """``count`` short walls at random places and angles in ROOM (seeded)."""
    rng = np.random.default_rng(seed)
    walls = []
    for _ in range(count):
        (x, y), angle, length = rng.uniform((-3.5, -2.5), (3.5, 2.5)), rng.uniform(0, 3.2), 0.4
        walls.append(((x, y), (x + length * math.cos(angle), y + length * math.sin(angle))))
    return walls


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10**6), st.floats(0.0, 0.3), st.floats(0.0, 0.2))
def test_the_near_grid_finds_the_lines_the_wide_grid_finds(seed, offset, sigma):
    """Returns of small gates looked up in the near grid: the same steps, bit for bit, as with
    the wide grid alone (a near grid that no gate fits)."""
    walls = ROOM + _clutter(seed, 40)
    pose = (0.3, -0.2, 0.1)
    scan = view(walls, pose, seed=seed % 1000)
    tracker = LineMapFilter(room_lines(walls))
    wide_only = LineMapFilter(room_lines(walls))
    wide_only.near_grid = wide_only.near_grid._replace(reach=-0.0)
    steps = []
    for filt in (tracker, wide_only):
        filt.start((pose[0] + offset, pose[1] - offset, pose[2]), (0.02 + sigma, 0.01 + sigma))
        first = filt.step(scan.points[scan.valid], None)
        second = filt.step(scan.points[scan.valid], (0.01, 0.0, 0.002))
        steps.append((first, second))
    for ours, theirs in zip(*steps, strict=True):
        assert (ours.status, ours.pairs) == (theirs.status, theirs.pairs)
        assert ours.state.tobytes() == theirs.state.tobytes()
        assert ours.state_covariance.tobytes() == theirs.state_covariance.tobytes()


def test_the_kernel_refuses_arguments_of_the_wrong_shape():
    from scanlines import _core

    tracker = LineMapFilter(room_lines(ROOM))
    tracker.start((0.0, 0.0, 0.0))
    grid, near, lines = tracker.grid, tracker.near_grid, tracker.lines
    args = [tracker.state, tracker.covariance, np.zeros(3), True, np.zeros(4), np.zeros(4),
            lines.rho, tracker.normals, lines.start, lines.end, lines.sides, grid.shape,
            grid.cell_start, grid.cell_lines, near.shape, near.cell_start, near.cell_lines,
            near.reach, tracker.settings.record(), 0]  # fmt: skip
    _core.filter_scan(*args)
    for position, wrong, message in [
        (0, np.zeros(5), "state has 7 values"), (2, np.zeros(2), "increment"),
        (5, np.zeros(3), "one length"), (6, lines.rho[:-1], "same lines"),
        (7, tracker.normals[:-1], "same lines"), (10, lines.sides[:-1], "same lines"),
        (12, grid.cell_start[:-1], "wide grid has nx"),
        (15, near.cell_start[:-1], "near grid has nx"), (17, math.nan, "near_reach"),
        (18, {**tracker.settings.record(), "solver": {"iterations": 0}}, "iterations"),
    ]:  # fmt: skip
        bad = list(args)
        bad[position] = wrong
        with pytest.raises(ValueError, match=message):
            _core.filter_scan(*bad)


def test_settings_out_of_their_domain_are_refused():
    from scanlines.errors import ParameterError

    with pytest.raises(ParameterError, match="gate_min"):
        FilterSettings(gate_min=0.6, gate_max=0.5)
    with pytest.raises(ParameterError, match="line_sigma"):
        FilterSettings(line_sigma=-1.0)
    with pytest.raises(ParameterError, match="normal_tolerance"):
        FilterSettings(normal_tolerance=2.0)
    with pytest.raises(ParameterError, match="normal_window"):
        FilterSettings(normal_window=0)


def test_localize_starts_at_the_scan_of_the_initial_time_where_the_clock_steps_back():
    truth = _circle(8)
    times = [1.0, 1.1, 1.3, 1.2, 1.4, 1.5, 1.6, 1.7]  # the clock steps back at the 4th
    scans = []
    for k, (pose, t) in enumerate(zip(truth, times, strict=True)):
        scan = view(ROOM, pose, seed=k, sigma=0.003)
        scans.append(Scan(scan.ranges, scan.angle_min, scan.angle_increment, pose=pose,
                          timestamp=t))  # fmt: skip
    lines, frame = room_lines(ROOM), LocalFrame()
    run = localize(enumerate(scans), lines, frame, (1.2, truth[3]))
    assert run.skipped == 3
    assert [t.index for t in run.tracked] == [3, 4, 5, 6, 7]
    # No scan within 10 ms of the time: the first after it, in the log's order.
    run = localize(enumerate(scans), lines, frame, (1.25, truth[2]))
    assert run.skipped == 2
    assert run.tracked[0].index == 2
    assert len(run.tracked) == 6


def test_a_dense_scan_is_subsampled_to_the_settings_points():
    truth = (-1.0, 0.5, 0.3)
    scan = view(ROOM, truth, seed=7, sigma=0.003)  # 541 returns
    for most in (0, 60):
        tracker = LineMapFilter(room_lines(ROOM), FilterSettings(max_points=most))
        tracker.start((truth[0] + 0.05, truth[1] - 0.04, truth[2] + 0.02))
        step = tracker.step(scan.points[scan.valid], None)
        assert step.aligned
        assert step.pose == pytest.approx(truth, abs=0.01)
        if most:
            assert step.pairs <= most
        else:
            assert step.pairs > 300


def test_a_scan_subsampled_to_one_return_keeps_its_first():
    """``max_points=1`` keeps the first return (numpy's linspace). Its position was 0 / 0, and
    the kernel read ``use[2**63]``: a build with ``-D_GLIBCXX_ASSERTIONS`` aborted there."""
    scan = view(ROOM, (-1.0, 0.5, 0.3), seed=7, sigma=0.003)
    tracker = LineMapFilter(room_lines(ROOM), FilterSettings(max_points=1))
    tracker.start((-1.0, 0.5, 0.3))
    step = tracker.step(scan.points[scan.valid], None)
    assert step.status == "too few returns on map lines"
    assert step.pairs <= 1
