"""The pose graph's tracking edges from a second tracker on recent scans (the submaps)."""

from __future__ import annotations

import itertools
import math

import numpy as np

from scanlines.extractor import Extractor
from scanlines.geometry.poses import compose, relative_pose
from scanlines.map.build import TrackedPose
from scanlines.map.loops import LoopCloser
from scanlines.map.submaps import LocalTracker, Submaps
from scanlines.map.tracking import TrackSettings
from scanlines.sim import World
from scanlines.sim.simulate import simulate
from scanlines.sim.world import polygon


def test_the_tracking_edges_are_the_local_poses_relative_poses():
    closer = LoopCloser()
    cov = np.eye(3) * 1e-6
    closer.add(0, (0.0, 0.0, 0.0), cov, local=(5.0, 5.0, math.pi / 2))
    closer.add(1, (1.0, 0.0, 0.0), cov, local=(5.0, 7.0, math.pi / 2))
    graph = closer.graph()
    assert np.allclose(graph.poses[1], (1.0, 0.0, 0.0))  # the graph starts at the poses
    assert np.allclose(graph.edges[0].measurement, (2.0, 0.0, 0.0))  # edges: the local ones


def _room() -> World:
    walls = [(-1, -2), (12, -2), (12, 2), (6, 2), (6, 3), (5, 3), (5, 2), (-1, 2)]
    return World([polygon(walls, "wall"), polygon([(2, -0.5), (2.4, -0.5), (2.4, 0.5), (2, 0.5)])])


def test_the_local_tracker_holds_the_drive_odometry_lets_drift():
    """Along a room with odometry that turns 1 deg per metre too much: the local tracker's
    relative pose from start to end stays near the truth, the odometry's does not."""
    world, extractor, rng = _room(), Extractor(), np.random.default_rng(3)
    local = LocalTracker(40, None, TrackSettings())
    truth = [(0.5 + 0.1 * k, 0.2 * math.sin(0.05 * k), 0.0) for k in range(80)]
    odometry, poses = [truth[0]], []
    for a, b in itertools.pairwise(truth):
        step = relative_pose(a, b)
        odometry.append(compose(odometry[-1], (step[0], step[1], step[2] + math.radians(0.1))))
    for k, (true, odo) in enumerate(zip(truth, odometry, strict=True)):
        scan = simulate(world, "lms_1deg", true, seed=int(rng.integers(1 << 30))).scan
        record = TrackedPose(k, None, odo, odo, odo, np.eye(3), "aligned")
        poses.append(local.track(record, scan, extractor(scan))[0])
    ends = [relative_pose(p[0], p[-1]) for p in (truth, odometry, poses)]
    odometry_turn = abs(ends[1][2] - ends[0][2])
    assert odometry_turn > math.radians(7)
    assert abs(ends[2][2] - ends[0][2]) < 0.2 * odometry_turn
    assert math.hypot(ends[2][0] - ends[0][0], ends[2][1] - ends[0][1]) < 0.05


def test_the_submaps_overlap_and_the_older_is_tracked_on():
    world, extractor = _room(), Extractor()
    submaps = Submaps(10)
    scan = simulate(world, "lms_1deg", (3.0, 0.0, 0.0), seed=1).scan
    extracted = extractor(scan)
    for k in range(12):
        submaps.add(extracted, k, (3.0, 0.0, 0.0))
    assert [m.scans_added for m in submaps._maps] == [7, 2]  # started at scans 5 and 10
    assert len(submaps.settled(3).rho) > 0
