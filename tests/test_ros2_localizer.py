"""The node's localisation without DDS: odometry by stamp, static frames, the live filter
against ``localize`` on the shipped Intel excerpt, the map's grid, and ``--restamp``'s
stamps."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("cyclonedds")

import itertools

from scanlines.data import sample
from scanlines.geometry.poses import compose, invert, relative_pose
from scanlines.io import open_log
from scanlines.map.align import LineSet
from scanlines.map.frame import LocalFrame
from scanlines.map.localize import localize
from scanlines.ros2.frames import OdometryBuffer, StaticFrames
from scanlines.ros2.localizer import Localizer
from scanlines.ros2.map_topics import CELL, OCCUPIED, rasterise
from scanlines.ros2.player import monotonic_stamps, steps_back


def intel_scans(count=400):
    with open_log(sample("intel")) as reader:
        return [scan for _, scan in zip(range(count), reader, strict=False)]


@pytest.fixture(scope="module")
def intel_map(tmp_path_factory):
    """A map of the Intel excerpt built from its odometry (``scanlines map``), read back."""
    import subprocess
    import sys

    from scanlines.map.localize import read_line_map

    path = tmp_path_factory.mktemp("live") / "intel.json"
    done = subprocess.run(
        [sys.executable, "-m", "scanlines", "map", str(sample("intel")), "--align",
         "--out", str(path)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return read_line_map(path)


def test_odometry_is_interpolated_at_a_stamp_and_exact_at_its_own():
    buffer = OdometryBuffer()
    buffer.add(2.0, (1.0, 0.0, math.radians(170)))
    buffer.add(1.0, (0.0, 0.0, 0.0))  # out of order
    buffer.add(3.0, (2.0, 2.0, math.radians(-170)))
    assert buffer.at(1.0) == (0.0, 0.0, 0.0)
    assert buffer.at(1.5) == pytest.approx((0.5, 0.0, math.radians(85)))
    x, y, yaw = buffer.at(2.5)
    assert (x, y) == pytest.approx((1.5, 1.0))
    assert abs(math.remainder(yaw - math.pi, math.tau)) < 1e-12  # the short way round
    assert buffer.at(0.5) is None
    assert buffer.at(3.5) is None
    buffer.add(2.0, (9.0, 9.0, 0.0))  # the same stamp again replaces
    assert buffer.at(2.0) == (9.0, 9.0, 0.0)
    assert len(buffer.times) == 3


def test_static_frames_chain_from_the_base_to_the_laser():
    frames = StaticFrames()
    frames.add("base_link", "mast", (0.2, 0.0, math.pi / 2))
    frames.add("/mast", "laser", (0.1, 0.0, 0.0))
    assert frames.lookup("base_link", "laser") == pytest.approx((0.2, 0.1, math.pi / 2))
    assert frames.lookup("base_link", "camera") is None
    assert frames.lookup("laser", "laser") == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("mounting", [None, (0.0, 0.0, 0.0), (0.12, -0.03, 0.05)])
def test_the_live_filter_gives_localizes_poses_for_the_same_scans(intel_map, mounting):
    """The base's odometry at each scan's stamp (the laser's pose less the mounting, as
    ``--play`` publishes it) through :class:`Localizer` gives the laser poses ``localize``
    gives on the same scans, and the base's pose is the laser's less the mounting."""
    lines, frame = intel_map
    scans = intel_scans()
    start = scans[0].pose
    expected = localize(enumerate(scans), lines, frame, (scans[0].timestamp, start))
    live = Localizer(lines, frame)
    mounted = mounting or (0.0, 0.0, 0.0)
    if mounting is not None:
        live.static.add("base_link", "laser", mounting)
    live.set_initial(1.0, compose(start, invert(mounted)))
    for k, (scan, want) in enumerate(zip(scans, expected.tracked, strict=True)):
        stamp = 1.0 + 0.025 * k  # monotonic, as --restamp makes them
        live.odometry.add(stamp, compose(scan.pose, invert(mounted)))
        got = live.localise(scan.points[scan.valid], stamp, "laser")
        assert got.status == want.status
        assert got.laser == pytest.approx(frame.world_pose(want.pose), abs=1e-9)
        if mounting is not None:
            assert got.base == pytest.approx(compose(got.laser, invert(mounting)), abs=1e-9)
        odometry = compose(scan.pose, invert(mounted))
        assert compose(got.map_to_odom, odometry) == pytest.approx(got.base, abs=1e-9)
    if mounting is None:  # the lever learnt stands for the mounting
        lever = (*expected.lever, 0.0)
        assert got.base == pytest.approx(compose(got.laser, invert(lever)), abs=1e-9)
        assert math.hypot(*expected.lever) > 0.01


def test_an_initial_pose_is_carried_by_the_odometry_to_the_next_scan(intel_map):
    lines, frame = intel_map
    scans = intel_scans(40)
    live = Localizer(lines, frame)
    for k, scan in enumerate(scans[:20]):
        live.odometry.add(1.0 + k, scan.pose)
        assert live.localise(scan.points[scan.valid], 1.0 + k, "laser") is None  # no pose yet
    then = compose(scans[14].pose, (0.05, -0.03, 0.02))  # the odometry a little off
    live.set_initial(15.0, then)  # where the robot was at the stamp of scan 14
    live.odometry.add(21.0, scans[20].pose)
    got = live.localise(scans[20].points[scans[20].valid], 21.0, "laser")
    carried = compose(then, relative_pose(scans[14].pose, scans[20].pose))
    run = localize(enumerate(scans[20:]), lines, frame, (scans[20].timestamp, carried))
    assert got.laser == pytest.approx(frame.world_pose(run.tracked[0].pose), abs=1e-9)


def test_an_initial_pose_from_another_clock_applies_at_the_next_scan(intel_map):
    """RViz stamps with the wall clock while a log plays on its own: a pose stamped more
    than a second ahead of the newest odometry applies at the next scan, uncarried."""
    lines, frame = intel_map
    scans = intel_scans(3)
    live = Localizer(lines, frame)
    live.odometry.add(346.0, scans[0].pose)
    assert live.set_initial(1.7e9, scans[1].pose) == 0.0
    assert live.set_initial(346.5, scans[1].pose) == 346.5  # within a second: the log's clock
    live.set_initial(1.7e9, scans[1].pose)
    live.odometry.add(347.0, scans[1].pose)
    got = live.localise(scans[1].points[scans[1].valid], 347.0, "laser")
    run = localize(enumerate(scans[1:]), lines, frame, (scans[1].timestamp, scans[1].pose))
    assert got.laser == pytest.approx(frame.world_pose(run.tracked[0].pose), abs=1e-9)


def test_the_map_grid_has_5_cm_cells_occupied_along_every_line():
    lines = LineSet(
        np.zeros(2), np.zeros(2), np.array([[0.0, 0.0], [1.0, -1.0]]),
        np.array([[2.0, 0.0], [1.0, 1.5]]),
    )  # fmt: skip
    frame = LocalFrame(10.0, -4.0)
    grid, (x0, y0) = rasterise(lines, frame)
    assert CELL == 0.05
    for a, b in zip(lines.start, lines.end, strict=True):
        for t in np.linspace(0, 1, 50):
            x, y = frame.world(a + t * (b - a))
            i, j = np.floor((np.array([y, x]) - [y0, x0]) / CELL).astype(int)
            assert grid[i, j] == OCCUPIED
    # 2 m + 2.5 m of lines at 5 cm: about 90 cells, and not many more
    assert 85 <= (grid == OCCUPIED).sum() <= 100
    assert x0 <= 10.0
    assert y0 <= -5.0
    assert x0 + grid.shape[1] * CELL >= 12.0


#: Logs' times: milliseconds over some days, as loggers print them.
times = st.lists(st.integers(0, 10**9).map(lambda ms: ms / 1000), min_size=1, max_size=60)


@settings(deadline=None)  # a loaded machine's pauses are no failure
@given(times)
def test_restamped_stamps_only_go_forward_and_keep_the_logs_positive_intervals(log):
    stamps = monotonic_stamps(log)
    assert len(stamps) == len(log)
    assert stamps[0] == log[0]
    steps = np.diff(stamps)
    assert np.all(steps > 0)
    for k, step in enumerate(steps):
        if log[k + 1] > log[k]:
            assert step == pytest.approx(log[k + 1] - log[k], abs=1e-6)  # stamps: ns
    back, _largest = steps_back(log)
    assert back == sum(1 for a, b in itertools.pairwise(log) if b <= a)
    if back == 0:
        assert stamps == pytest.approx(log, abs=1e-6)


def test_restamping_the_intel_excerpt_uses_the_median_where_its_clock_steps_back():
    scans = intel_scans(10_000)
    log = [scan.timestamp for scan in scans]
    back, largest = steps_back(log)
    assert back >= 7
    assert largest > 0.3
    stamps = monotonic_stamps(log)
    positive = [b - a for a, b in itertools.pairwise(log) if b > a]
    usual = float(np.median(positive))
    for k in range(len(log) - 1):
        want = log[k + 1] - log[k] if log[k + 1] > log[k] else usual
        assert stamps[k + 1] - stamps[k] == pytest.approx(want)
