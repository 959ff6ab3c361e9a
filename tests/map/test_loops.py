"""Loop closure: a wrong closure between two identical corridors refused, the true one kept."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from scanlines.geometry.poses import compose, relative_pose
from scanlines.map.loops import LoopCloser, LoopSettings
from scanlines.map.posegraph import Edge, PoseGraph, edge_errors, optimise, optimise_least_squares
from scanlines.map.tracking import TrackSettings
from scanlines.sim import World
from scanlines.sim.simulate import simulate
from scanlines.sim.world import polygon

#: Corridor A's outer wall (y = -1), with two niches; corridor B's is its point reflection
#: about (8, 2), so a scan in B heading -x is the scan in A at the reflected pose.
_A_WALL = [(0, -1), (5, -1), (5, -1.4), (5.8, -1.4), (5.8, -1), (9.5, -1), (9.5, -1.4),
           (10.1, -1.4), (10.1, -1), (16, -1)]  # fmt: skip


def two_corridors() -> World:
    """Two identical corridors (A: y in [-1, 1], B: y in [3, 5]) either side of a block,
    joined at both ends (x in [0, 2] and [14, 16])."""
    outer = _A_WALL + [(16 - x, 4 - y) for x, y in _A_WALL]
    block = [(2, 1), (14, 1), (14, 3), (2, 3)]
    return World([polygon(outer, "wall"), polygon(block, "box")])


def _leg(start, end, step: float = 0.1) -> list[tuple[float, float, float]]:
    (x0, y0), (x1, y1) = start, end
    n = max(1, round(math.hypot(x1 - x0, y1 - y0) / step))
    heading = math.atan2(y1 - y0, x1 - x0)
    return [(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, heading) for k in range(n)]


def _turn(x: float, y: float, start: float, end: float) -> list[tuple[float, float, float]]:
    n = max(1, round(abs(end - start) / 0.1))
    return [(x, y, start + (end - start) * k / n) for k in range(n)]


def trajectory() -> list[tuple[float, float, float]]:
    """Along A (+x), up through the far junction, back along B (-x), down through the
    near junction, and along A again for 5 m: the true loop closes at the near junction."""
    half = math.pi / 2
    return (
        _leg((1, 0), (15, 0)) + _turn(15, 0, 0, half) + _leg((15, 0), (15, 4))
        + _turn(15, 4, half, math.pi) + _leg((15, 4), (1, 4))
        + _turn(1, 4, math.pi, 3 * half) + _leg((1, 4), (1, 0))
        + _turn(1, 0, 3 * half, 2 * math.pi) + _leg((1, 0), (6, 0))
    )  # fmt: skip


def drifting_odometry(truth, rng):
    """Dead reckoning of the true increments with noise and a heading bias of 0.6 deg per
    metre driven, and each increment's covariance (the tracker's odometry model)."""
    model = TrackSettings()
    poses, covariances = [truth[0]], [model.increment_covariance((0.0, 0.0, 0.0))]
    for a, b in itertools.pairwise(truth):
        step = relative_pose(a, b)
        moved = math.hypot(step[0], step[1])
        noisy = (
            step[0] + rng.normal(0, 0.005), step[1] + rng.normal(0, 0.005),
            step[2] + math.radians(0.6) * moved + rng.normal(0, 0.002),
        )  # fmt: skip
        poses.append(compose(poses[-1], noisy))
        covariances.append(model.increment_covariance(step))
    return poses, covariances


def corridor(truth, pose) -> str:
    x, y = pose[0], pose[1]
    if 2 < x < 14:
        return "A" if y < 2 else "B"
    return "junction"


@pytest.fixture(scope="module")
def corridor_run():
    rng = np.random.default_rng(7)
    world = two_corridors()
    truth = trajectory()
    odometry, covariances = drifting_odometry(truth, rng)
    # a wide search, so that the scans of B are tried against A's (4 m apart)
    closer = LoopCloser(LoopSettings(radius=5.0, min_travel=8.0, every=3))
    for k, (pose, cov) in enumerate(zip(odometry, covariances, strict=True)):
        scan = simulate(world, "lms_1deg", truth[k], seed=int(rng.integers(1 << 30))).scan
        closer.add(k, pose, cov, scan)
    return truth, odometry, closer.close()


def test_the_world_is_identical_in_both_corridors():
    world = two_corridors()
    a = simulate(world, "lms_1deg", (6.0, 0.0, 0.0), seed=1).scan
    b = simulate(world, "lms_1deg", (10.0, 4.0, math.pi), seed=1).scan
    assert np.allclose(a.ranges, b.ranges, atol=0.05)


def test_the_tempting_closure_between_the_corridors_is_refused(corridor_run):
    truth, _, result = corridor_run
    across = [
        r for r in result.refusals
        if {corridor(truth, truth[r.scan_i]), corridor(truth, truth[r.scan_j])} == {"A", "B"}
    ]  # fmt: skip
    assert across, "no candidate between the corridors was tried"
    assert any(r.reason == "disagrees with odometry" for r in across)
    for c in result.closures:  # every accepted closure is true
        true = relative_pose(truth[c.scan_i], truth[c.scan_j])
        assert math.hypot(c.pose[0] - true[0], c.pose[1] - true[1]) < 0.1
        assert abs(math.remainder(c.pose[2] - true[2], 2 * math.pi)) < math.radians(2)


def test_the_true_closure_at_the_junction_is_accepted(corridor_run):
    truth, odometry, result = corridor_run
    returned = [c for c in result.closures if c.scan_j > len(truth) - 60 and c.scan_i < 60]
    assert returned, f"refusals: {result.refused}"
    end = len(truth) - 1
    drift = math.hypot(odometry[end][0] - truth[end][0], odometry[end][1] - truth[end][1])
    fixed = math.hypot(result.poses[end][0] - truth[end][0], result.poses[end][1] - truth[end][1])
    assert drift > 1.0
    assert fixed < 0.2 * drift


def _circle_graph(n: int, rng, wrong: bool):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    truth = np.column_stack((10 * np.cos(t), 10 * np.sin(t), t + np.pi / 2))
    info = np.diag([1e4, 1e4, 2.5e5])
    graph = PoseGraph(np.zeros((n, 3)))
    graph.poses[0] = truth[0]
    for k in range(1, n):
        z = np.array(relative_pose(truth[k - 1], truth[k])) + rng.normal(0, [0.01, 0.01, 0.002])
        graph.add(Edge(k - 1, k, tuple(z), info))
        graph.poses[k] = compose(graph.poses[k - 1], z)
    graph.add(Edge(0, n - 1, relative_pose(truth[0], truth[n - 1]), info, "loop"))
    if wrong:
        graph.add(Edge(0, n // 2, (1.0, 0.0, 0.0), info, "loop"))
    return truth, graph


def test_the_solvers_agree_and_close_a_circle():
    truth, graph = _circle_graph(300, np.random.default_rng(1), wrong=False)
    gauss_newton = optimise(graph)
    trust_region = optimise_least_squares(graph)
    assert gauss_newton.cost < 1e-3 * gauss_newton.initial_cost
    assert gauss_newton.cost == pytest.approx(trust_region.cost, rel=1e-3)
    before = np.hypot(*(graph.poses[:, :2] - truth[:, :2]).T)
    after = np.hypot(*(gauss_newton.poses[:, :2] - truth[:, :2]).T)
    assert after[-1] < 0.1 * before[-1]  # the loop's end is pinned to its start
    assert after.max() < before.max()


def test_a_wrong_edge_stands_out_in_its_error():
    _, graph = _circle_graph(300, np.random.default_rng(2), wrong=True)
    errors = edge_errors(graph, optimise(graph).poses)
    assert int(np.argmax(errors)) == len(graph.edges) - 1
