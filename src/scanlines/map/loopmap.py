"""A tracked map with its loops closed: the scans' poses optimised, the map fused again."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from scanlines.extractor import Extractor
from scanlines.geometry.transform import to_world
from scanlines.map.build import MapBuild, TrackedPose, build_map
from scanlines.map.fusion import FusionSettings, LineMap
from scanlines.map.loops import LoopCloser, LoopResult, LoopSettings
from scanlines.map.submaps import LocalTracker
from scanlines.map.tracking import TrackSettings
from scanlines.scan import Scan

__all__ = ["build_closed_map", "closed_records", "loop_summary"]


def build_closed_map(
    indexed: Iterable[tuple[int, Scan]],
    extractor: Extractor | None = None,
    *,
    poses=None,
    settings: FusionSettings | None = None,
    track: TrackSettings | None = None,
    loops: LoopSettings | None = None,
    hold_out: Callable[[int], bool] | None = None,
    on_scan: Callable[[int], None] | None = None,
    on_query: Callable[[int, int], None] | None = None,
    source: str | None = None,
) -> tuple[MapBuild, LoopResult]:
    """:func:`~scanlines.map.build.build_map` with tracking, then the loops closed
    (:class:`~scanlines.map.loops.LoopCloser`) and the map fused again from the optimised
    poses (held-out poses moved with them). The graph's tracking edges come from a second
    tracker on the last ``loops.submap_scans`` scans
    (:class:`~scanlines.map.submaps.LocalTracker`; 0: from the map's tracker). Returns the
    build (its ``tracked`` records as the tracker left them) and the loop result."""
    closer = LoopCloser(loops)
    features: dict[int, Any] = {}
    indices: list[int] = []
    size = closer.settings.submap_scans
    local = LocalTracker(size, settings, track or TrackSettings()) if size else None

    def keep(record: TrackedPose, scan: Scan, extracted) -> None:
        evidence = scan if record.mapped else None
        if local is None:
            closer.add(record.index, record.pose, record.covariance, evidence)
        else:
            pose, covariance = local.track(record, scan, extracted)
            closer.add(record.index, record.pose, covariance, evidence, local=pose)
        indices.append(record.index)
        if extracted is not None:
            features[len(indices) - 1] = extracted

    build = build_map(
        indexed, extractor, poses=poses, settings=settings, track=track or TrackSettings(),
        hold_out=hold_out, on_scan=on_scan, source=source, on_tracked=keep,
    )  # fmt: skip
    result = closer.close(on_query)
    line_map = LineMap(settings, build.frame)
    for node, extracted in features.items():
        pose = tuple(float(v) for v in result.poses[node])
        line_map.add(to_world(extracted, pose), indices[node], pose)
    build.line_map = line_map
    for node, index in enumerate(indices):
        if index in build.held_out:
            build.held_out[index] = tuple(float(v) for v in result.poses[node])
    build.poses = f"{build.poses}, loops closed ({len(result.closures)} closures)"
    return build, result


def closed_records(build: MapBuild, result: LoopResult) -> list[TrackedPose]:
    """The tracked records with the optimised poses in place of the tracked ones."""
    return [
        record._replace(pose=tuple(float(v) for v in pose))
        for record, pose in zip(build.tracked, result.poses, strict=True)
    ]


def loop_summary(build: MapBuild, result: LoopResult) -> dict[str, Any]:
    """The closures accepted (world frame poses of both scans), refused, and the solver."""
    frame = build.frame
    moved = np.hypot(*(result.poses[:, :2] - np.array([t.pose[:2] for t in build.tracked])).T)
    return {
        "settings": result.settings.to_dict(),
        "candidates": result.candidates,
        "accepted": len(result.closures),
        "refused": result.refused,
        "solver": result.solver,
        "moved_m": {"median": float(np.median(moved)), "max": float(np.max(moved))},
        "closures": [
            {**c.to_dict(),
             "world_i": list(frame.world_pose(tuple(result.poses[c.node_i]))),
             "world_j": list(frame.world_pose(tuple(result.poses[c.node_j])))}
            for c in result.closures
        ],
    }  # fmt: skip
