"""The range noise an extractor without a sensor profile learns from the scans it sees."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np

from scanlines.sensor.profile import noise_samples_of, pooled_noise_line
from scanlines.steps.noise import NoiseLine

#: Scans of one sensor the noise line is learned from, then frozen.
LEARNED_SCANS = 300

Geometry = tuple[int, float, float]
"""A sensor: beam count, first angle and increment, as the kernels take them (float32)."""


@dataclass
class _Pool:
    samples: list[np.ndarray] = field(default_factory=list)
    ranges: list[np.ndarray] = field(default_factory=list)


class NoiseLearner:
    """Learns each sensor's noise line from its first :data:`LEARNED_SCANS` scans.

    A sensor is its geometry (beam count, first angle, increment). The first scan of a
    sensor is extracted with its own noise estimate; the noise samples of the scans seen
    are pooled, and the line of the pool (:func:`~scanlines.sensor.profile.estimate_profile`'s
    measure of the same scans) is measured again after 1, 2, 4, ... scans and frozen after
    the last of :data:`LEARNED_SCANS`: each scan is extracted with the line of the scans
    before it. The samples are those of the ranges the kernels take (float32), so a scan
    teaches the same whether it came as a :class:`~scanlines.Scan` or as a row of a batch.

    Each thread learns on its own: a scan is extracted with the line of the scans the
    same thread gave before it, so one learner shared by threads gives every thread what a
    learner of its own would, whatever the scheduling.
    """

    def __init__(self, scans: int | None = None) -> None:
        self.scans = LEARNED_SCANS if scans is None else scans
        self._local = threading.local()

    def _state(self) -> tuple[dict[Geometry, _Pool], dict[Geometry, NoiseLine | None]]:
        local = self._local
        if not hasattr(local, "pools"):
            local.pools, local.lines = {}, {}
        return local.pools, local.lines

    def line(self, geometry: Geometry) -> NoiseLine | None:
        """The noise line this thread has learned so far for ``geometry``; None before its
        first scan (or while its scans hold too few samples to measure one)."""
        return self._state()[1].get(geometry)

    def frozen(self, geometry: Geometry) -> bool:
        pools, lines = self._state()
        return geometry in lines and geometry not in pools

    def learn(self, geometry: Geometry, ranges: np.ndarray, valid: np.ndarray, cos, sin) -> None:
        """Pool one scan's noise samples (its float32 ``ranges``, ``valid`` mask and bearing
        tables relative to beam 0); a scan of a frozen sensor changes nothing."""
        if self.frozen(geometry):
            return
        pools, lines = self._state()
        pool = pools.setdefault(geometry, _Pool())
        sample, at = noise_samples_of(ranges, valid, cos, sin)
        pool.samples.append(sample)
        pool.ranges.append(at)
        seen = len(pool.samples)
        if seen >= self.scans or seen & (seen - 1) == 0:  # the last, or a power of two
            lines[geometry] = pooled_noise_line(pool.samples, pool.ranges)
        if seen >= self.scans:
            del pools[geometry]
