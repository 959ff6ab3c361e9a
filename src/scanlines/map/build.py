"""Building a line map from a log: extract every scan, move it by its pose, fuse."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from scanlines.extractor import Extractor
from scanlines.geometry.poses import Pose, compose, relative_pose
from scanlines.geometry.transform import points_to_world, to_world
from scanlines.map.align import AlignSettings, LineSet, _near, align_scan
from scanlines.map.filter import FilterSettings, LineMapFilter
from scanlines.map.frame import LocalFrame, MapError, check_extent, check_pose, frame_at
from scanlines.map.fusion import FusionSettings, LineMap
from scanlines.scan import Scan

__all__ = ["MapBuild", "build_map"]

PoseSource = Callable[[int, Scan], Pose | None]

#: The scans a map line needs before tracking aligns scans to it.
SUPPORT = 3
#: Tracking matches the lines within this (metres) of the scan at the last pose.
NEAR_MARGIN = 1.5
#: The filter's settings for tracking on the map being built (``map --align``): the looser
#: odometry noise of the earlier tracker (1 cm + 10 % of the distance, 0.5 deg + 10 % of the
#: turn + 1 % per metre), a gate of at least 15 cm, and no correction refused (the map so far
#: is the robot's own recent view). On the raw Intel scans these gave an ATE of 0.47 m, the
#: localisation defaults 1.26 m (docs/MEASUREMENTS.md).
MAPPING = FilterSettings(
    odometry_floor=0.01, odometry_per_metre=0.1, turn_floor=math.radians(0.5),
    turn_per_radian=0.1, turn_per_metre=0.01, gate_min=0.15, max_chi_square=1000.0,
)  # fmt: skip


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
    track: FilterSettings | None = None
    not_aligned: int = 0
    unaligned_first: int = 0
    tracked: list[TrackedPose] = field(default_factory=list)
    #: The filter's predicted state (and its covariance) at each held-out scan.
    held_state: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

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
    track: FilterSettings | None = None,
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
        Track instead with the filter of ``scanlines localize``
        (:class:`~scanlines.map.filter.LineMapFilter`, these its settings): each scan's
        pose predicted from the last tracked state and the increment of ``poses``
        (odometry as the prior, its errors learnt on the way), its returns matched to the
        lines of the map built so far that :data:`SUPPORT` scans have seen; a scan that
        does not fit is kept out of the map (counted in ``not_aligned``). Every pose is
        kept in ``tracked``. Excludes ``align``.
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
    tracker = None if track is None else _MapTracker(track)
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
            record = tracker.track(index, scan, pose, line_map, held)
            _count(build, record)
            check_extent(record.pose, frame, f"{where} {index}")
            if held:
                build.held_out[index] = record.pose
                build.held_state[index] = tracker.held
            if not record.mapped:
                continue
            pose = record.pose
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


class _MapTracker:
    """The filter on the map being built: the lines it matches are refreshed each scan
    (those near the predicted scan, seen by :data:`SUPPORT` scans)."""

    def __init__(self, settings: FilterSettings) -> None:
        self.settings = settings
        self.filter: LineMapFilter | None = None
        self.odometry: Pose | None = None
        self.pose: Pose | None = None
        self.held: tuple[np.ndarray, np.ndarray] | None = None

    def track(self, index: int, scan: Scan, odometry: Pose, line_map: LineMap, held: bool):
        """The :class:`TrackedPose` of a scan at ``odometry`` (local frame); a held-out scan
        is predicted only, and the tracker does not move on from it."""
        increment = None if self.odometry is None else relative_pose(self.odometry, odometry)
        lines = LineSet(*line_map.settled(SUPPORT))
        if self.filter is None:
            self.filter = LineMapFilter(lines, self.settings)
            self.filter.start(odometry if self.pose is None else compose(self.pose, increment))
            increment = None
        points = scan.points[scan.valid].astype(np.float64)
        if held:
            return self._predict(index, scan, odometry, increment)
        if not len(lines.rho):
            # the first scans: nothing to align to yet, mapped where the odometry says
            step = self.filter.step(np.zeros((0, 2)), increment)
            self.odometry, self.pose = odometry, step.pose
            return TrackedPose(index, scan.timestamp, odometry, step.predicted, step.pose,
                               step.covariance, "first")  # fmt: skip
        last = self.filter.state
        assert last is not None
        if len(points):
            lines = _near(lines, points_to_world(points, last[:3]), NEAR_MARGIN)
        self.filter.use_lines(lines)
        step = self.filter.step(points, increment)
        self.odometry, self.pose = odometry, step.pose
        status = "aligned" if step.aligned else "did not fit"
        return TrackedPose(index, scan.timestamp, odometry, step.predicted, step.pose,
                           step.covariance, status)  # fmt: skip

    def _predict(self, index: int, scan: Scan, odometry: Pose, increment) -> TrackedPose:
        """A held-out scan: the prediction (no returns matched), the filter left as it was."""
        tracker = self.filter
        assert tracker is not None
        saved = (tracker.state, tracker.covariance, tracker._first)
        step = tracker.step(np.zeros((0, 2)), increment)
        tracker.state, tracker.covariance, tracker._first = saved
        self.held = (step.state.copy(), step.state_covariance.copy())
        return TrackedPose(index, scan.timestamp, odometry, step.predicted, step.predicted,
                           step.state_covariance[:3, :3].copy(), "held out")  # fmt: skip


def _count(build: MapBuild, record: TrackedPose) -> None:
    """Count a tracked scan by its status and keep it."""
    if record.status == "aligned":
        build.aligned += 1
    elif record.status == "first":
        build.unaligned_first += 1
    elif record.status == "did not fit":
        build.not_aligned += 1
    build.tracked.append(record)
