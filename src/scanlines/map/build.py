"""Building a line map from a log: extract every scan, move it by its pose, fuse."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from scanlines.extractor import Extractor
from scanlines.geometry.poses import Pose
from scanlines.geometry.transform import to_world
from scanlines.map.align import AlignSettings, LineSet, align_scan
from scanlines.map.frame import LocalFrame, MapError, check_extent, check_pose, frame_at
from scanlines.map.fusion import FusionSettings, LineMap
from scanlines.map.tracking import OdometryTracker, TrackFit, TrackSettings, track_points
from scanlines.scan import Scan

__all__ = ["MapBuild", "build_map"]

PoseSource = Callable[[int, Scan], Pose | None]


class TrackedPose(NamedTuple):
    """A tracked scan (``track``): its index and time, its odometry (or given) pose, its
    predicted pose and its tracked pose (local frame), the pose's covariance, and its
    ``status``: ``"aligned"``, ``"first"`` (mapped at its prediction: the map had no line
    yet), ``"did not fit"`` (the prediction stands; not mapped) or ``"held out"``."""

    index: int
    timestamp: float | None
    odometry: Pose
    predicted: Pose
    pose: Pose
    covariance: np.ndarray
    status: str

    @property
    def aligned(self) -> bool:
        return self.status == "aligned"

    @property
    def mapped(self) -> bool:
        return self.status in ("aligned", "first")


@dataclass
class MapBuild:
    """A built map and how it was made."""

    line_map: LineMap
    poses: str
    pose_note: str | None = None
    scans: int = 0
    without_pose: int = 0
    held_out: dict[int, Pose] = field(default_factory=dict)
    last_index: int = -1
    align: AlignSettings | None = None
    aligned: int = 0
    track: TrackSettings | None = None
    not_aligned: int = 0
    unaligned_first: int = 0
    tracked: list[TrackedPose] = field(default_factory=list)

    @property
    def segments(self) -> int:
        return self.line_map.segments_seen

    @property
    def frame(self) -> LocalFrame:
        """The map's local frame (``held_out`` poses and the map's lines are in it)."""
        return self.line_map.frame


def build_map(
    indexed: Iterable[tuple[int, Scan]],
    extractor: Extractor | None = None,
    *,
    poses: PoseSource | None = None,
    settings: FusionSettings | None = None,
    hold_out: Callable[[int], bool] | None = None,
    on_scan: Callable[[int], None] | None = None,
    align: AlignSettings | None = None,
    track: TrackSettings | None = None,
    source: str | None = None,
) -> MapBuild:
    """The line map of ``(index, scan)`` pairs, streamed (one scan in memory at a time).

    Parameters
    ----------
    indexed:
        ``reader.enumerate()`` of a log, or any ``(index, scan)`` pairs in log order.
    extractor:
        The extractor (default: ``Extractor()``, the default method).
    poses:
        Each scan's sensor pose in the world: :class:`~scanlines.map.poses.LogPoses`
        (the default), :class:`~scanlines.map.poses.TrajectoryPoses` or
        :class:`~scanlines.map.poses.RegistrationOdometry`. Scans it gives no pose are
        counted in ``without_pose`` and not mapped.
    hold_out:
        Scans for which it is true are not mapped; their poses are kept in ``held_out``
        (for :func:`scanlines.map.holdout.score_held_out`), in the map's frame.
    align:
        Align each scan to the map built so far before fusing it
        (:mod:`scanlines.map.align`; ``None``: the poses as given).
    track:
        Track instead (:mod:`scanlines.map.tracking`): each scan's pose predicted from the
        last tracked pose and the increment of ``poses`` (odometry as the prior), aligned
        to the map built so far; a scan that does not fit is kept out of the map (counted
        in ``not_aligned``). Every pose is kept in ``tracked``. Excludes ``align``.
    source:
        The log's name, for error messages.

    The map is built in a local frame (:mod:`scanlines.map.frame`): the world less the
    first pose's position rounded to the metre (``build.frame``).

    Raises
    ------
    MapError
        Naming ``source`` and the scan, if a pose is not finite or beyond
        :data:`~scanlines.map.frame.MAX_COORDINATE`, or a pose or a segment is beyond
        :data:`~scanlines.map.frame.MAX_EXTENT` from the map's origin.
    """
    from scanlines.map.poses import LogPoses

    if track is not None and align is not None:
        raise ValueError("build_map: give align or track, not both")
    extractor = extractor or Extractor()
    poses = poses or LogPoses()
    line_map = LineMap(settings)
    name, note = getattr(poses, "name", type(poses).__name__), getattr(poses, "note", None)
    if track is not None:
        name, note = f"{name} as odometry, each scan tracked on the map so far", None
    elif align is not None:
        name, note = f"{name}, aligned to the map so far", None
    elif note:
        name = f"{name}, unaligned"
    build = MapBuild(line_map, poses=name, align=align, pose_note=note, track=track)
    tracker = None if track is None else OdometryTracker(track)
    frame: LocalFrame | None = None
    where = f"{source}: scan" if source else "scan"
    for index, scan in indexed:
        pose = poses(index, scan)
        build.last_index = index
        if on_scan is not None:
            on_scan(index)
        if pose is None:
            build.without_pose += 1
            continue
        check_pose(pose, f"{where} {index}")
        if frame is None:
            frame = line_map.frame = frame_at(pose)
        pose = frame.pose(pose)
        check_extent(pose, frame, f"{where} {index}")
        held = hold_out is not None and hold_out(index)
        if tracker is not None:
            fit, predicted = _track(tracker, scan, pose, line_map, held)
            _record(build, index, scan, (pose, predicted), fit, held)
            check_extent(fit.pose, frame, f"{where} {index}")
            if held:
                build.held_out[index] = fit.pose
            if not build.tracked[-1].mapped:
                continue
            pose = fit.pose
        elif held:
            build.held_out[index] = pose
            continue
        if align is not None:
            fit = align_scan(scan, pose, LineSet(*line_map.settled(align.support)), align)
            pose = fit.pose
            build.aligned += fit.used
        try:
            line_map.add(to_world(extractor(scan), pose), index, pose)
        except MapError as error:
            raise MapError(f"{source}: {error}" if source else str(error)) from None
        build.scans += 1
    return build


def _track(tracker: OdometryTracker, scan: Scan, odometry: Pose, line_map: LineMap, held: bool):
    """The tracked pose of a scan at ``odometry`` (local frame); a held-out scan is
    predicted only, and the tracker does not move on from it."""
    predicted, prior = tracker.predict(odometry)
    settings = tracker.settings
    if held:
        return TrackFit(predicted, False, 0, prior, "held out"), predicted
    lines = LineSet(*line_map.settled(settings.support))
    if not len(lines.rho):  # the first scans: nothing to align to yet
        tracker.advance(odometry, predicted)
        return TrackFit(predicted, False, 0, prior, None), predicted
    fit = track_points(scan.points[scan.valid], predicted, prior, lines, settings)
    tracker.advance(odometry, fit.pose)
    return fit, predicted


def _record(build: MapBuild, index: int, scan: Scan, poses, fit, held: bool) -> None:
    """Keep a tracked scan's poses (``poses``: its odometry pose and its prediction)."""
    if held:
        status = "held out"
    elif fit.used:
        status = "aligned"
        build.aligned += 1
    elif fit.reason is None:
        status = "first"
        build.unaligned_first += 1
    else:
        status = "did not fit"
        build.not_aligned += 1
    build.tracked.append(
        TrackedPose(index, scan.timestamp, *poses, fit.pose, fit.covariance, status)
    )
