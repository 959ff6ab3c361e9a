"""Simulate one scan of a world from a sensor pose, with its exact ground truth."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from scanlines.scan import Scan
from scanlines.sim.family import get_sensor
from scanlines.sim.noise import NoiseModel, apply_noise
from scanlines.sim.sensors import SensorSpec
from scanlines.sim.truth import compute_truth
from scanlines.sim.world import World
from scanlines.truth import BeamStatus, Truth

__all__ = ["SimScan", "as_rng", "depth_jumps", "simulate"]


@dataclass(frozen=True, eq=False)
class SimScan:
    """A simulated scan and everything needed to score an extraction of it.

    Attributes
    ----------
    scan:
        The measured :class:`~scanlines.Scan` (its ``pose`` is the sensor pose).
    truth:
        The exact :class:`~scanlines.evaluation.truth.Truth`.
    world:
        The world scanned.
    sensor:
        The sensor, with the noise model actually used.
    bias_scale:
        The scan's bias draw ``u`` in ``[-1, 1]``; the range bias at range ``r`` is
        ``sensor.noise.bias_at(r, u)``.
    """

    scan: Scan
    truth: Truth
    world: World
    sensor: SensorSpec
    bias_scale: float


def as_rng(seed: int | np.random.Generator | None) -> np.random.Generator:
    """``numpy.random.default_rng(seed)``, passing a generator through unchanged."""
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.default_rng(seed)


def depth_jumps(world: World, edge: np.ndarray, full_circle: bool) -> np.ndarray:
    """Consecutive beam pairs that straddle two surfaces that do not meet.

    Returns one boolean per pair ``(k, k + 1)``; for a full-circle scan one more for
    the pair ``(n - 1, 0)``. Pairs where either beam hits nothing are ``False``.
    """
    e = np.asarray(edge, dtype=np.intp)
    nxt = np.roll(e, -1)
    key = world.surface_key(e)
    both = (e >= 0) & (nxt >= 0)
    jump = both & (key != np.roll(key, -1)) & ~world.adjacent(e, nxt)
    return jump if full_circle else jump[:-1]


def _returning_hits(
    world: World, origin: tuple[float, float], bearings: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The edge each beam hits and its exact range; a beam that hits glass stops there and
    nothing comes back (edge -1, range inf)."""
    hits = world.cast(origin, bearings)
    edge, true_ranges = hits.edge, hits.ranges
    if not world.edge_returns.all():
        glass = (edge >= 0) & ~world.edge_returns[np.maximum(edge, 0)]
        edge, true_ranges = np.where(glass, -1, edge), np.where(glass, np.inf, true_ranges)
    return edge, true_ranges


def simulate(
    world: World,
    sensor: str | SensorSpec = "lms_1deg",
    pose: Sequence[float] = (0.0, 0.0, 0.0),
    *,
    seed: int | np.random.Generator | None = None,
    noise: NoiseModel | None = None,
    timestamp: float | None = None,
) -> SimScan:
    """Scan ``world`` from ``pose`` with ``sensor`` and compute the exact truth.

    Parameters
    ----------
    world:
        The world.
    sensor:
        A preset name (see :data:`~scanlines.sim.sensors.SENSORS`) or a
        :class:`~scanlines.sim.sensors.SensorSpec`.
    pose:
        Sensor pose ``(x, y, theta)`` in the world frame (metres, radians).
    seed:
        Seed or generator of the noise (``numpy.random.default_rng(seed)``): the same
        seed gives the same scan.
    noise:
        Overrides the sensor's noise model; ``NoiseModel()`` gives exact ranges.
    timestamp:
        Stored in the scan.

    Beams that hit a shape with ``returns=False`` (glass) have no return and no edge
    in the truth (:attr:`BeamStatus.NO_HIT`). The truth's don't-care events use the
    noise model actually applied (see :mod:`scanlines.sim.truth`).

    Returns
    -------
    SimScan

    Examples
    --------
    >>> from scanlines.sim import World, wall
    >>> sim = simulate(World([wall((2, -5), (2, 5))]), "lms_1deg", seed=1, noise=NoiseModel())
    >>> round(float(sim.scan.ranges[90]), 6)    # beam 90 is the 0 deg beam
    2.0
    """
    spec = get_sensor(sensor)
    if noise is not None:
        spec = spec.with_noise(noise)
    x, y, theta = (float(v) for v in pose)
    angles = spec.angles
    edge, true_ranges = _returning_hits(world, (x, y), angles + theta)
    circle = spec.full_circle
    measured = apply_noise(
        true_ranges,
        depth_jumps(world, edge, circle),
        spec.noise,
        as_rng(seed),
        range_min=spec.range_min,
        range_max=spec.range_max,
    )
    scan = Scan(
        measured.ranges,
        angle_min=spec.angle_min,
        angle_increment=spec.angle_increment,
        range_min=spec.range_min,
        range_max=spec.range_max,
        timestamp=timestamp,
        pose=(x, y, theta),
    )
    returned = np.isin(measured.status, (BeamStatus.HIT, BeamStatus.MIXED, BeamStatus.OUTLIER))
    if not np.array_equal(scan.valid, returned):  # pragma: no cover - internal consistency
        raise AssertionError("simulated returns disagree with Scan.valid")
    truth = compute_truth(
        world, (x, y, theta), angles, edge, true_ranges, measured.status,
        full_circle=circle, sigma=spec.noise.effective_sigma,
    )  # fmt: skip
    return SimScan(scan=scan, truth=truth, world=world, sensor=spec, bias_scale=measured.bias_scale)
