"""Ground truth of hand-built scenes: breakpoints, corners and segments at known beams."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scanlines.sim import (
    BeamStatus,
    NoiseModel,
    SensorSpec,
    Truth,
    World,
    box,
    compute_truth,
    polyline,
    random_scene,
    round_pillar,
    sensor_to_world,
    simulate,
    wall,
)

EXACT = NoiseModel()
# lms_1deg: beam k has bearing (k - 90) deg, so beam 90 looks straight ahead.


def _exact(
    world: World, pose: tuple[float, float, float] = (0.0, 0.0, 0.0), sensor: str = "lms_1deg"
) -> Truth:
    return simulate(world, sensor, pose, noise=EXACT).truth


def _truth_with_status(world: World, changes: dict[int, BeamStatus]) -> Truth:
    """Truth of an exact lms_1deg scan from the origin with some beam statuses changed."""
    angles = np.radians(np.arange(-90.0, 90.0))
    hits = world.cast((0, 0), angles)
    status = np.where(hits.edge >= 0, BeamStatus.HIT, BeamStatus.NO_HIT).astype(np.int8)
    for beam, st in changes.items():
        status[beam] = st
    return compute_truth(
        world, (0, 0, 0), angles, hits.edge, hits.ranges, status, full_circle=False
    )


WALL_X2 = World([wall((2, -10), (2, 10))])


def test_plain_wall_is_one_segment_with_exact_line_and_endpoints() -> None:
    truth = _exact(WALL_X2)
    # the wall spans bearings +-atan(10 / 2) = +-78.69 deg: beams 12..168 -> 12..179 clipped
    assert truth.breakpoints.tolist() == []
    assert truth.corners.tolist() == []
    seg = truth.segments
    assert len(seg) == 1
    assert (seg.first[0], seg.last[0]) == (12, 168)
    np.testing.assert_allclose([seg.rho[0], seg.alpha[0]], [2.0, 0.0], atol=1e-12)
    a = math.radians(12 - 90)
    np.testing.assert_allclose(seg.start[0], [2.0, 2.0 * math.tan(a)])
    np.testing.assert_allclose(seg.end[0], [2.0, 2.0 * math.tan(math.radians(78))])
    assert seg.n_returns[0] == 157
    np.testing.assert_allclose(truth.incidence[90 + 60], math.radians(60))


def test_box_seen_at_a_corner_gives_one_corner_at_the_nearer_beam() -> None:
    # a 1 m box turned 45 deg; its near vertex at (2.2929, 0.05), bearing 1.249 deg:
    # between beam 91 (1 deg, 0.249 deg away) and beam 92 (2 deg, 0.751 deg away)
    world = World([box((3.0, 0.05), 1.0, 1.0, angle=math.pi / 4)])
    truth = _exact(world)
    assert truth.corners.tolist() == [91]
    np.testing.assert_allclose(truth.corner_points[0], [3.0 - math.sqrt(0.5), 0.05], atol=1e-12)
    assert truth.breakpoints.tolist() == []  # nothing behind the box: no gap between returns
    seg = truth.segments
    assert len(seg) == 2
    assert (seg.last[0], seg.first[1]) == (91, 92)
    # the two faces facing the sensor: normals (from the sensor) at -45 and +45 deg
    np.testing.assert_allclose(np.sort(np.degrees(seg.alpha)), [-45.0, 45.0], atol=1e-9)


def test_box_in_front_of_a_wall_gives_two_breakpoints() -> None:
    # box front face x = 2.5, |y| <= 0.5: beams with |bearing| <= 11.31 deg (79..101)
    world = World([wall((5, -10), (5, 10)), box((3, 0), 1.0, 1.0)])
    truth = _exact(world)
    assert truth.breakpoints.tolist() == [78, 101]
    assert truth.corners.tolist() == []
    # the wall spans +-63.43 deg: beams 27..153
    assert truth.breakpoint_runs.tolist() == [[52, 23], [23, 52]]
    seg = truth.segments
    assert list(zip(seg.first.tolist(), seg.last.tolist(), strict=True)) == [
        (27, 78),
        (79, 101),
        (102, 153),
    ]
    assert seg.edge[0] == seg.edge[2] == 0
    np.testing.assert_allclose(seg.rho, [5.0, 2.5, 5.0])


def test_door_gap_with_a_wall_behind() -> None:
    # front wall x = 3 with an opening for 0.5 < y < 1.5 (bearings 9.46..26.57 deg),
    # back wall x = 5 visible only through the opening
    world = World([wall((3, -10), (3, 0.5)), wall((3, 1.5), (3, 10)), wall((5, -2), (5, 8))])
    truth = _exact(world)
    assert truth.breakpoints.tolist() == [99, 116]
    assert truth.corners.tolist() == []
    seg = truth.segments
    through = seg.first == 100
    assert seg.last[through].tolist() == [116]
    assert seg.rho[through].tolist() == [5.0]


def test_a_single_dropout_inside_a_wall_is_bridged() -> None:
    truth = _truth_with_status(WALL_X2, {90: BeamStatus.DROPOUT})
    assert truth.breakpoints.tolist() == []
    assert len(truth.segments) == 1
    assert truth.segments.n_returns[0] == 156
    assert truth.dropouts.tolist() == [90]


def test_two_missing_beams_end_a_cluster() -> None:
    truth = _truth_with_status(WALL_X2, {90: BeamStatus.DROPOUT, 91: BeamStatus.OUT_OF_RANGE})
    assert truth.breakpoints.tolist() == [89]
    assert truth.segments.first.tolist() == [12, 92]
    assert truth.segments.last.tolist() == [89, 168]


def test_outliers_and_mixed_pixels_count_as_missing_and_are_listed() -> None:
    one = _truth_with_status(WALL_X2, {50: BeamStatus.OUTLIER})
    assert one.breakpoints.tolist() == []
    assert one.outliers.tolist() == [50]
    two = _truth_with_status(WALL_X2, {50: BeamStatus.OUTLIER, 51: BeamStatus.MIXED})
    assert two.breakpoints.tolist() == [49]
    assert two.mixed_pixels.tolist() == [51]


def test_one_missing_beam_at_a_depth_jump_is_a_breakpoint_before_it() -> None:
    world = World([wall((5, -10), (5, 10)), box((3, 0), 1.0, 1.0)])
    truth = _truth_with_status(world, {79: BeamStatus.MIXED})
    assert truth.breakpoints.tolist() == [78, 101]
    truth = _truth_with_status(world, {78: BeamStatus.MIXED})
    assert truth.breakpoints.tolist() == [77, 101]


def test_round_pillar_has_breakpoints_but_no_corners_or_segments() -> None:
    world = World([wall((5, -10), (5, 10)), round_pillar((3, 0), 0.4, sides=32)])
    truth = _exact(world)
    assert truth.corners.tolist() == []
    assert len(truth.breakpoints) == 2
    assert np.all(truth.segments.edge == 0)  # only the wall pieces are segments
    assert truth.on_curve[90]
    assert not truth.on_curve[30]


def test_touching_shapes_meet_in_a_breakpoint_not_a_corner() -> None:
    # two walls meeting at (3, 0.02) (bearing 0.38 deg) without sharing a vertex of one
    # shape: beam 90 (0 deg) is the last on the first wall
    world = World([wall((3, -5), (3, 0.02)), wall((3, 0.02), (6, 5))])
    truth = _exact(world)
    assert truth.corners.tolist() == []
    assert truth.breakpoints.tolist() == [90]
    joined = _exact(World([polyline([(3, -5), (3, 0.02), (6, 5)])]))
    assert joined.corners.tolist() == [90]
    assert joined.breakpoints.tolist() == []


def test_segment_lines_are_in_the_sensor_frame() -> None:
    # the wall y = 2 in the world, seen from a sensor turned to face +y: x = 2 in its frame
    world = World([wall((-10, 2), (10, 2))])
    truth = _exact(world, pose=(0.0, 0.0, math.pi / 2))
    np.testing.assert_allclose([truth.segments.rho[0], truth.segments.alpha[0]], [2, 0], atol=1e-12)
    hit_world = sensor_to_world(truth.hit_points, truth.pose)
    np.testing.assert_allclose(hit_world[90], [0.0, 2.0], atol=1e-12)
    np.testing.assert_allclose(hit_world[truth.true_return][:, 1], 2.0)


def _ring(angle_min_deg: float) -> SensorSpec:
    return SensorSpec(
        name="ring",
        n_beams=360,
        angle_min=math.radians(angle_min_deg),
        angle_increment=math.radians(1.0),
        range_min=0.0,
        range_max=30.0,
    )


def test_full_circle_square_room_wraps_across_the_seam() -> None:
    # square turned 0.2 deg: vertices at bearings 45.2, 135.2, -134.8, -44.8 deg.
    # Beam k has bearing -179.5 + k deg; the seam lies inside the left wall.
    room = box((0, 0), 4.0, 4.0, angle=math.radians(0.2), kind="room")
    sensor = _ring(-179.5)
    assert sensor.full_circle
    truth = simulate(World([room]), sensor, noise=EXACT).truth
    assert truth.full_circle
    assert truth.corners.tolist() == [45, 135, 225, 315]
    assert truth.breakpoints.tolist() == []
    seg = truth.segments
    assert len(seg) == 4
    wraps = seg.first > seg.last
    assert wraps.sum() == 1
    assert (seg.first[wraps][0], seg.last[wraps][0]) == (315, 44)
    assert seg.n_returns.sum() == 360
    np.testing.assert_allclose(seg.rho, 2.0, atol=1e-12)


def test_full_circle_breakpoint_across_the_seam() -> None:
    # one wall in front; behind the sensor nothing: the last return before the gap
    # (circularly) ends the only cluster
    sensor = _ring(0.0)
    truth = simulate(World([wall((2, -3), (2, 3))]), sensor, noise=EXACT).truth
    # bearings -56.3..56.3 deg: beams 0..56 and 304..359, one cluster across the seam
    assert truth.breakpoints.tolist() == [56]
    seg = truth.segments
    assert (seg.first.tolist(), seg.last.tolist()) == ([304], [56])
    assert truth.breakpoint_runs.tolist() == [[113, 113]]


@pytest.mark.parametrize("seed", range(6))
def test_truth_invariants_on_noisy_random_scenes(seed: int) -> None:
    sensor = ("lms_1deg", "lms_05deg", "tim571", "urg04lx")[seed % 4]
    sim = random_scene(seed, sensor).scan(seed)
    truth, scan = sim.truth, sim.scan
    returned = truth.true_return
    # every true return is a valid beam of the scan, and measured close to its surface
    assert np.all(scan.valid[returned])
    err = np.abs(scan.ranges[returned] - truth.true_ranges[returned])
    assert err.max() < 0.2
    # events sit on true returns; segments are separated by events
    assert np.all(returned[truth.breakpoints])
    assert np.all(returned[truth.corners])
    seg = truth.segments
    assert np.all(returned[seg.first])
    assert np.all(returned[seg.last])
    assert len(seg) <= len(truth.breakpoints) + len(truth.corners) + 1
    on_line = returned & ~truth.on_curve
    assert seg.n_returns.sum() == on_line.sum()
    # every segment's hit points lie on its true line
    for k in range(len(seg)):
        beams = np.arange(seg.first[k], seg.last[k] + 1)
        beams = beams[returned[beams]]
        pts = truth.hit_points[beams]
        d = pts @ [math.cos(seg.alpha[k]), math.sin(seg.alpha[k])] - seg.rho[k]
        np.testing.assert_allclose(d, 0.0, atol=1e-9)
        assert np.all(truth.edge[beams] == seg.edge[k])
