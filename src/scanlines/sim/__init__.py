"""Simulated 2D laser scans with exact ground truth.

Build a world from polylines and polygons, scan it with a real sensor's beam layout
and noise, and get the scan together with its exact breakpoints, corners and
segments::

    from scanlines.sim import random_scene

    scene = random_scene(seed=7, sensor="tim571")
    sim = scene.scan(seed=7)            # SimScan: .scan (a scanlines.Scan) and .truth
    sim.truth.breakpoints, sim.truth.corners, sim.truth.segments

Or by hand::

    from scanlines.sim import World, box, wall, simulate

    world = World([wall((3, -4), (3, 4)), box((2, 0), 0.5, 0.5)])
    sim = simulate(world, "lms_1deg", pose=(0, 0, 0), seed=1)

Only numpy is needed. The truth conventions are in :mod:`scanlines.sim.truth` (the
truth types, re-exported here, in :mod:`scanlines.truth`), the noise model in
:mod:`scanlines.sim.noise`, the sensor numbers in :mod:`scanlines.sim.sensors`, the
sensor family (randomised sensors and their four corner sensors) in
:mod:`scanlines.sim.family`.
"""

from __future__ import annotations

from scanlines.sim.family import (
    corner_sensors,
    family_names,
    family_sensors,
    get_sensor,
    random_sensor,
)
from scanlines.sim.noise import NO_RETURN, NoiseModel, NoisyRanges, apply_noise
from scanlines.sim.raycast import RayHits, cast_rays
from scanlines.sim.scenes import CLUTTER_KINDS, SCENE_KINDS, Scene, random_scene
from scanlines.sim.sensors import SENSORS, SensorSpec
from scanlines.sim.simulate import SimScan, depth_jumps, simulate
from scanlines.sim.truth import compute_truth, hesse_line, sensor_to_world, world_to_sensor
from scanlines.sim.world import (
    Shape,
    World,
    box,
    polygon,
    polyline,
    regular_polygon,
    round_pillar,
    wall,
)
from scanlines.truth import BeamStatus, TrueSegments, Truth

__all__ = [
    "CLUTTER_KINDS",
    "NO_RETURN",
    "SCENE_KINDS",
    "SENSORS",
    "BeamStatus",
    "NoiseModel",
    "NoisyRanges",
    "RayHits",
    "Scene",
    "SensorSpec",
    "Shape",
    "SimScan",
    "TrueSegments",
    "Truth",
    "World",
    "apply_noise",
    "box",
    "cast_rays",
    "compute_truth",
    "corner_sensors",
    "depth_jumps",
    "family_names",
    "family_sensors",
    "get_sensor",
    "hesse_line",
    "polygon",
    "polyline",
    "random_scene",
    "random_sensor",
    "regular_polygon",
    "round_pillar",
    "sensor_to_world",
    "simulate",
    "wall",
    "world_to_sensor",
]
