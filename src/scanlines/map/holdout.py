"""A map scored on the scans it did not see (``scanlines eval --map``)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from scanlines.geometry.transform import points_to_world
from scanlines.map.align import AlignSettings, LineSet, align_scan, nearest_segments
from scanlines.map.build import MapBuild, build_map
from scanlines.map.fusion import FusionSettings, MapLines
from scanlines.map.tracking import TrackSettings, track_points
from scanlines.scan import Scan

__all__ = ["MapScore", "distances_to_lines", "evaluate_map", "loop_lines", "score_held_out"]

#: The smallest distance a return may be from a line and still count as covered.
MIN_TOLERANCE = 0.05


@dataclass(frozen=True)
class MapScore:
    """What ``scanlines eval --map`` reports (metres; shares in [0, 1])."""

    held_out_scans: int
    mapped_scans: int
    returns: int
    coverage: float
    median_distance: float
    median_range: float
    sigma_at_median_range: float
    lines: int
    segments_fused: int
    segments_per_line: float
    map_length: float
    lines_per_100m: float
    loop_lines: int
    poses: str
    localised_coverage: float = math.nan
    localised_median_distance: float = math.nan
    localised_scans: int = 0

    @property
    def median_in_sigmas(self) -> float:
        return self.median_distance / self.sigma_at_median_range

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "median_in_sigmas": self.median_in_sigmas}


def distances_to_lines(points: np.ndarray, lines: MapLines) -> np.ndarray:
    """Distance of each ``K x 2`` world point to the nearest map line segment (inf if none)."""
    return nearest_segments(points, lines.start, lines.end)[0]


def loop_lines(lines: MapLines, first: int, last: int, share: float = 0.1) -> int:
    """Map lines seen both in the first and in the last ``share`` of the scans
    ``first..last``: walls a loop came back to and fused into one line."""
    span = max(last - first, 1)
    early = lines.first_scan <= first + share * span
    late = lines.last_scan >= last - share * span
    return int(np.count_nonzero(early & late))


def score_held_out(
    indexed: Iterable[tuple[int, Scan]],
    build: MapBuild,
    sigma_at: Callable[[np.ndarray], np.ndarray],
) -> MapScore:
    """Score ``build``'s map on its held-out scans, read again from ``indexed``: at the
    poses given, and where the map was built with alignment, also localised (each held-out
    scan aligned to the finished map first, as a robot localising with it would). All of
    it in the map's local frame, where ``build.held_out`` and the lines are."""
    lines = build.line_map.lines()
    target = LineSet(lines.rho, lines.alpha, lines.start, lines.end)
    locate = None if build.align is None else build.align.replace(damping=1.0)
    priors = {t.index: t.covariance for t in build.tracked if t.status == "held out"}
    distances, tolerances, ranges, localised = [], [], [], []
    moved = 0
    for index, scan in indexed:
        pose = build.held_out.get(index)
        if pose is None:
            continue
        valid = scan.valid
        r = scan.ranges[valid].astype(np.float64)
        distances.append(distances_to_lines(points_to_world(scan.points[valid], pose), lines))
        tolerances.append(np.maximum(3.0 * sigma_at(r), MIN_TOLERANCE))
        ranges.append(r)
        if locate is not None or build.track is not None:
            fit = (
                align_scan(scan, pose, target, locate) if locate is not None
                else track_points(scan.points[valid], pose, priors[index], target, build.track)
            )  # fmt: skip
            moved += fit.used
            world = points_to_world(scan.points[valid], fit.pose)
            localised.append(distances_to_lines(world, lines))
    d, tol, r = (np.concatenate(a) if a else np.zeros(0) for a in (distances, tolerances, ranges))
    near = _localised(localised, tol, moved)
    median_range = float(np.median(r)) if len(r) else math.nan
    length = float(lines.lengths.sum())
    fused = int(lines.segments.sum())
    return MapScore(
        held_out_scans=len(build.held_out),
        mapped_scans=build.scans,
        returns=len(d),
        coverage=float(np.mean(d <= tol)) if len(d) else math.nan,
        median_distance=float(np.median(d)) if len(d) else math.nan,
        median_range=median_range,
        sigma_at_median_range=float(sigma_at(np.array([median_range]))[0]),
        lines=len(lines),
        segments_fused=fused,
        segments_per_line=fused / len(lines) if len(lines) else math.nan,
        map_length=length,
        lines_per_100m=100.0 * len(lines) / length if length > 0 else math.nan,
        loop_lines=loop_lines(lines, 0, build.last_index),
        poses=build.poses,
        **near,
    )


def _localised(distances: list[np.ndarray], tolerances: np.ndarray, moved: int) -> dict:
    """The localised fields of a :class:`MapScore` (none without them)."""
    if not distances:
        return {}
    d = np.concatenate(distances)
    if not len(d):
        return {}
    return {
        "localised_coverage": float(np.mean(d <= tolerances)),
        "localised_median_distance": float(np.median(d)),
        "localised_scans": moved,
    }


def evaluate_map(
    open_indexed: Callable[[], Any],
    extractor,
    sigma_at: Callable[[np.ndarray], np.ndarray],
    *,
    poses=None,
    settings: FusionSettings | None = None,
    every: int = 10,
    limit: int | slice | None = None,
    align: AlignSettings | None = None,
    track: TrackSettings | None = None,
    source: str | None = None,
    on_scan: Callable[[str, int], None] | None = None,
    loops=None,
) -> tuple[MapScore, MapBuild]:
    """Build the map from all scans but every ``every``-th, then score it on those.

    ``open_indexed()`` opens the log afresh (a context manager giving a reader with
    ``enumerate()``); the log is read twice, one scan in memory at a time; ``limit``: only
    its first ``limit`` scans, or those a slice of scan indices selects; ``source``: the
    log's name, for error messages; ``align`` or ``track``: how the map is built
    (:func:`~scanlines.map.build.build_map`), the held-out scans then also localised the
    same way; ``loops`` (a :class:`~scanlines.map.loops.LoopSettings`, with ``track``): the
    loops closed (:func:`~scanlines.map.loopmap.build_closed_map`), the held-out scans' poses
    moved with the optimised ones; ``on_scan(stage, index)``: called for each scan read,
    ``stage`` ``"mapping"`` on the first pass and ``"scoring"`` on the second.
    """
    from scanlines.reader_options import select_scans

    selection = limit if isinstance(limit, slice) else slice(limit)

    def indexed(reader, stage: str):
        for index, scan in select_scans(reader.enumerate(), selection):
            if on_scan is not None:
                on_scan(stage, index)
            yield index, scan

    with open_indexed() as reader:
        if loops is not None and track is not None:
            from scanlines.map.loopmap import build_closed_map

            build, _ = build_closed_map(
                indexed(reader, "mapping"), extractor, poses=poses, settings=settings,
                track=track, loops=loops, hold_out=lambda index: index % every == 0,
                source=source,
            )  # fmt: skip
        else:
            build = build_map(
                indexed(reader, "mapping"), extractor, poses=poses, settings=settings,
                hold_out=lambda index: index % every == 0, align=align, track=track,
                source=source,
            )  # fmt: skip
    with open_indexed() as reader:
        score = score_held_out(indexed(reader, "scoring"), build, sigma_at)
    return score, build
