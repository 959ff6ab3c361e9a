"""Tracking on the last few scans only: the relative poses of a pose graph's tracking edges."""

from __future__ import annotations

import numpy as np

from scanlines.geometry.poses import Pose
from scanlines.geometry.transform import to_world
from scanlines.map.align import LineSet
from scanlines.map.fusion import FusionSettings, LineMap
from scanlines.map.tracking import OdometryTracker, TrackFit, TrackSettings, track_points

__all__ = ["LocalTracker", "Submaps"]


class Submaps:
    """The lines of the last few scans: two overlapping line maps of ``size`` scans each,
    a new one started every ``size / 2`` scans; the older, the fuller, is tracked on."""

    def __init__(self, size: int, settings: FusionSettings | None = None) -> None:
        self.size, self.settings = size, settings
        self._maps: list[LineMap] = []

    def add(self, extracted, index: int, pose: Pose) -> None:
        """A scan's features (sensor frame) at ``pose``."""
        if not self._maps or self._maps[-1].scans_added >= max(1, self.size // 2):
            self._maps = [*self._maps[-1:], LineMap(self.settings)]
        world = to_world(extracted, pose)
        for line_map in self._maps:
            line_map.add(world, index, pose)

    def settled(self, floor: int) -> LineSet:
        """The older map's lines seen by ``floor`` scans or more."""
        if not self._maps:
            return LineSet(*LineMap(self.settings).settled(floor))
        return LineSet(*self._maps[0].settled(floor))


class LocalTracker:
    """A second tracker, on :class:`Submaps` of its own poses instead of the whole map.

    Tracked on the whole map, every lap after the first follows the first lap's map and
    its bend, and so do the relative poses of its scans; tracked on the last ``size`` scans
    alone, each lap's relative poses are its own, and the closures between laps can
    average them (``docs/decisions/pose-graph.md``). Its poses drift like odometry: only
    their relative poses are used.
    """

    def __init__(self, size: int, fusion: FusionSettings | None, track: TrackSettings) -> None:
        self.settings = track
        self.submaps = Submaps(size, fusion)
        self._tracker = OdometryTracker(track)

    def track(self, record, scan, extracted) -> tuple[Pose, np.ndarray]:
        """The local pose and covariance of a scan the map's tracker recorded as
        ``record`` (:class:`~scanlines.map.build.TrackedPose`); ``extracted``, its features
        when the map takes it, go into the submaps."""
        predicted, prior = self._tracker.predict(record.odometry)
        if record.status == "held out":
            return predicted, prior
        lines = self.submaps.settled(self.settings.support)
        if len(lines.rho):
            fit = track_points(scan.points[scan.valid], predicted, prior, lines, self.settings)
        else:
            fit = TrackFit(predicted, False, 0, prior)
        self._tracker.advance(record.odometry, fit.pose)
        if extracted is not None and (fit.used or not len(lines.rho)):
            self.submaps.add(extracted, record.index, fit.pose)
        return fit.pose, fit.covariance
