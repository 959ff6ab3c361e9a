"""The range noise an extractor without a sensor profile learns from the scans it sees."""

from __future__ import annotations

import threading

import numpy as np

from scanlines.scan import Scan
from scanlines.sensor.profile import noise_samples, pooled_noise_line
from scanlines.steps.noise import NoiseLine

#: Scans of one sensor the noise line is learned from, then frozen.
LEARNED_SCANS = 300

Geometry = tuple[int, float, float]


class NoiseLearner:
    """Learns each sensor's noise line from its first :data:`LEARNED_SCANS` scans.

    A sensor is its geometry (beam count, first angle, increment). The first scan of a
    sensor is extracted with its own noise estimate; the noise samples of the scans seen
    are pooled, and the line of the pool (:func:`~scanlines.sensor.profile.estimate_profile`'s
    measure of the same scans) is measured again after 1, 2, 4, ... scans and frozen after
    the last of :data:`LEARNED_SCANS`: each scan is extracted with the line of the scans
    before it. Safe to share between threads.
    """

    def __init__(self, scans: int | None = None) -> None:
        self.scans = LEARNED_SCANS if scans is None else scans
        self._lock = threading.Lock()
        self._pools: dict[Geometry, tuple[list[np.ndarray], list[np.ndarray]]] = {}
        self._lines: dict[Geometry, NoiseLine | None] = {}
        self._frozen: set[Geometry] = set()

    @staticmethod
    def geometry(scan: Scan) -> Geometry:
        return (len(scan), float(scan.angle_min), float(scan.angle_increment))

    def line(self, geometry: Geometry) -> NoiseLine | None:
        """The noise line learned so far for ``geometry``; None before its first scan (or
        while its scans hold too few samples to measure one)."""
        return self._lines.get(geometry)

    def frozen(self, geometry: Geometry) -> bool:
        return geometry in self._frozen

    def learn(self, scan: Scan) -> None:
        """Pool ``scan``'s noise samples (a scan of a frozen sensor changes nothing)."""
        geometry = self.geometry(scan)
        if geometry in self._frozen:
            return
        sample, at = noise_samples(scan)
        with self._lock:
            if geometry in self._frozen:
                return
            samples, ranges = self._pools.setdefault(geometry, ([], []))
            samples.append(sample)
            ranges.append(at)
            seen = len(samples)
            if seen >= self.scans or seen & (seen - 1) == 0:  # the last, or a power of two
                self._lines[geometry] = pooled_noise_line(samples, ranges)
            if seen >= self.scans:
                self._frozen.add(geometry)
                del self._pools[geometry]
