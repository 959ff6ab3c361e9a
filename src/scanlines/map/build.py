"""Building a line map from a log: extract every scan, move it by its pose, fuse."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from scanlines.extraction import Extraction
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
    on_tracked: Callable[[TrackedPose, Scan, Extraction | None], None] | None = None,
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
    on_tracked:
        With ``track``: called with each tracked scan's record, the scan and its features
        in the sensor frame (``None`` when it is not mapped), for a pose graph
        (:mod:`scanlines.map.loopmap`).

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
    poses = poses or LogPoses()
    name, note = _poses_named(poses, align, track)
    build = MapBuild(LineMap(settings), name, note, align=align, track=track)
    builder = _Builder(build, extractor or Extractor(), hold_out, on_tracked, source)
    for index, scan in indexed:
        pose = poses(index, scan)
        build.last_index = index
        if on_scan is not None:
            on_scan(index)
        if pose is None:
            build.without_pose += 1
            continue
        builder.add(index, scan, pose)
    return build


def _poses_named(poses: PoseSource, align, track) -> tuple[str, str | None]:
    """What the map's poses are (``MapBuild.poses``) and the pose source's note."""
    name, note = getattr(poses, "name", type(poses).__name__), getattr(poses, "note", None)
    if track is not None:
        return f"{name} as odometry, each scan tracked on the map so far", None
    if align is not None:
        return f"{name}, aligned to the map so far", None
    return (f"{name}, unaligned" if note else name), note


class _Builder:
    """The stages of :func:`build_map` for a scan with a pose: the pose in the map's local
    frame (the first pose sets it), the pose the scan is mapped at (tracked, aligned or as
    given; none: held out, or tracked and not mapped), its features fused at it."""

    def __init__(self, build: MapBuild, extractor: Extractor, hold_out, on_tracked, source):
        self.build, self.extractor = build, extractor
        self.hold_out, self.on_tracked, self.source = hold_out, on_tracked, source
        self.tracker = None if build.track is None else OdometryTracker(build.track)
        self.frame: LocalFrame | None = None
        self.where = f"{source}: scan" if source else "scan"

    def add(self, index: int, scan: Scan, pose: Pose) -> None:
        pose = self.local_pose(index, pose)
        held = self.hold_out is not None and self.hold_out(index)
        if self.tracker is not None:
            pose = self.tracked_pose(index, scan, pose, held)
        elif held:
            self.build.held_out[index] = pose
            return
        if pose is not None:
            self.fuse(index, scan, self.aligned_pose(scan, pose))

    def local_pose(self, index: int, pose: Pose) -> Pose:
        """``pose`` (world) in the map's frame, checked."""
        check_pose(pose, f"{self.where} {index}")
        if self.frame is None:
            self.frame = self.build.line_map.frame = frame_at(pose)
        pose = self.frame.pose(pose)
        check_extent(pose, self.frame, f"{self.where} {index}")
        return pose

    def tracked_pose(self, index: int, scan: Scan, pose: Pose, held: bool) -> Pose | None:
        """The tracked pose of the scan at odometry ``pose``, recorded; ``None`` if it is
        not mapped."""
        build = self.build
        fit, predicted = _track(self.tracker, scan, pose, build.line_map, held)
        _record(build, index, scan, (pose, predicted), fit, held)
        check_extent(fit.pose, self.frame, f"{self.where} {index}")
        if held:
            build.held_out[index] = fit.pose
        if not build.tracked[-1].mapped:
            if self.on_tracked is not None:
                self.on_tracked(build.tracked[-1], scan, None)
            return None
        return fit.pose

    def aligned_pose(self, scan: Scan, pose: Pose) -> Pose:
        """``pose``, aligned to the map so far if the build aligns."""
        align = self.build.align
        if align is None:
            return pose
        fit = align_scan(scan, pose, LineSet(*self.build.line_map.settled(align.support)), align)
        self.build.aligned += fit.used
        return fit.pose

    def fuse(self, index: int, scan: Scan, pose: Pose) -> None:
        """The scan's features fused into the map at ``pose``."""
        extracted = self.extractor(scan)
        if self.on_tracked is not None and self.tracker is not None:
            self.on_tracked(self.build.tracked[-1], scan, extracted)
        try:
            self.build.line_map.add(to_world(extracted, pose), index, pose)
        except MapError as error:
            raise MapError(f"{self.source}: {error}" if self.source else str(error)) from None
        self.build.scans += 1


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
