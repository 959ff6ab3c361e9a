"""The range noise an extractor without a sensor profile learns from the scans it sees."""

from __future__ import annotations

import threading

import numpy as np

from scanlines.scan import Scan
from scanlines.sensor_profile import noise_samples, pooled_noise_line
from scanlines.steps.noise import NoiseLine

#: Scans of one sensor the noise line is learned from, then frozen.
LEARNED_SCANS = 300

Geometry = tuple[int, float, float]


class NoiseLearner:
    """Learns each sensor's noise line from its first :data:`LEARNED_SCANS` scans.

    A sensor is its geometry (beam count, first angle, increment). Until its line is
    frozen, each scan is extracted with its own noise estimate and its samples are pooled;
    the line of the pooled samples (:func:`~scanlines.sensor_profile.estimate_profile`'s
    measure of the same scans) is frozen at the last of them. Safe to share between threads.
    """

    def __init__(self, scans: int | None = None) -> None:
        self.scans = LEARNED_SCANS if scans is None else scans
        self._lock = threading.Lock()
        self._pools: dict[Geometry, tuple[list[np.ndarray], list[np.ndarray]]] = {}
        self._lines: dict[Geometry, NoiseLine | None] = {}

    @staticmethod
    def geometry(scan: Scan) -> Geometry:
        return (len(scan), float(scan.angle_min), float(scan.angle_increment))

    def line(self, geometry: Geometry) -> NoiseLine | None:
        """The frozen noise line of ``geometry``, or None while it is still learned."""
        return self._lines.get(geometry)

    def frozen(self, geometry: Geometry) -> bool:
        return geometry in self._lines

    def learn(self, scan: Scan) -> None:
        """Pool ``scan``'s noise samples (a scan of a frozen sensor changes nothing)."""
        geometry = self.geometry(scan)
        if geometry in self._lines:
            return
        sample, at = noise_samples(scan)
        with self._lock:
            if geometry in self._lines:
                return
            samples, ranges = self._pools.setdefault(geometry, ([], []))
            samples.append(sample)
            ranges.append(at)
            if len(samples) >= self.scans:
                self._lines[geometry] = pooled_noise_line(samples, ranges)
                del self._pools[geometry]
