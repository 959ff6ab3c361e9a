"""Building a line map from a log: extract every scan, move it by its pose, fuse."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from scanlines.extractor import Extractor
from scanlines.io.transform import to_world
from scanlines.map.align import AlignSettings, LineSet, align_scan
from scanlines.map.frame import LocalFrame, MapError, check_extent, check_pose, frame_at
from scanlines.map.fusion import FusionSettings, LineMap
from scanlines.poses import Pose
from scanlines.scan import Scan

__all__ = ["MapBuild", "build_map"]

PoseSource = Callable[[int, Scan], Pose | None]


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

    extractor = extractor or Extractor()
    poses = poses or LogPoses()
    line_map = LineMap(settings)
    name, note = getattr(poses, "name", type(poses).__name__), getattr(poses, "note", None)
    if align is not None:
        name, note = f"{name}, aligned to the map so far", None
    elif note:
        name = f"{name}, unaligned"
    build = MapBuild(line_map, poses=name, align=align, pose_note=note)
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
        if hold_out is not None and hold_out(index):
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
