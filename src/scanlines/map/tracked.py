"""Tracked poses (``scanlines map --align``, ``scanlines localize``): what tracking did, and
the poses written as TUM with their covariances beside them."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.geometry.poses import Pose

__all__ = ["tracking_summary", "write_tracked"]


def _wrap(angle: float) -> float:
    return float(math.remainder(angle, 2.0 * math.pi))


def tracking_summary(tracked, frame) -> dict[str, Any]:
    """What tracking did (``tracked``: :class:`~scanlines.map.build.TrackedPose` records,
    ``frame`` their local frame): the scans aligned, not aligned (kept out of the map),
    the first scans mapped unaligned; how far alignment moved each pose from its prediction
    and from the pose source's (odometry) pose, median and max; the median standard
    deviation of the aligned poses (metres, degrees)."""
    rows = [t for t in tracked if t.status != "held out"]
    aligned = [t for t in tracked if t.aligned]

    def spread(values: list[float]) -> dict[str, float | None]:
        if not values:
            return {"median": None, "max": None}
        return {"median": float(np.median(values)), "max": float(np.max(values))}

    def shift(a: Pose, b: Pose) -> float:
        return math.hypot(a[0] - b[0], a[1] - b[1])

    def turn(a: Pose, b: Pose) -> float:
        return math.degrees(abs(_wrap(a[2] - b[2])))

    return {
        "scans": len(rows),
        "aligned": len(aligned),
        "not_aligned": sum(1 for t in tracked if t.status == "did not fit"),
        "first_unaligned": sum(1 for t in tracked if t.status == "first"),
        "correction_m": spread([shift(t.pose, t.predicted) for t in aligned]),
        "correction_deg": spread([turn(t.pose, t.predicted) for t in aligned]),
        "from_source_m": spread([shift(t.pose, t.odometry) for t in rows]),
        "from_source_deg": spread([turn(t.pose, t.odometry) for t in rows]),
        "sigma_m": spread(
            [math.sqrt(max(t.covariance[0, 0], t.covariance[1, 1])) for t in aligned]
        ),
        "sigma_deg": spread([math.degrees(math.sqrt(t.covariance[2, 2])) for t in aligned]),
        "origin": list(frame.origin),
    }


def write_tracked(tracked, frame, path) -> tuple[Path, Path, int]:
    """The tracked poses of ``tracked`` (held out too, in log order) as a TUM file at
    ``path`` (world frame) and their covariances as a JSON file beside it
    (``NAME.cov.json``); scans without a timestamp are left out (their count returned)."""
    from scanlines.map.export import dumps
    from scanlines.map.poses import write_tum
    from scanlines.outputs import write_text_atomically

    path = Path(path)
    timed = [t for t in tracked if t.timestamp is not None]
    write_tum(path, [(t.timestamp, frame.world_pose(t.pose)) for t in timed])
    sidecar = path.with_name(path.stem + ".cov.json")
    document = {
        "poses": path.name,
        "covariance": "3 x 3 of x (m), y (m), theta (rad), row-major, per pose of the file",
        "status": "aligned, did not fit (the odometry's prediction), first (mapped at its "
        "prediction), held out, lost (the filter explains too few returns: searching the map "
        "for its pose), found (found again by that search)",
        "records": [
            {"timestamp": t.timestamp, "scan": t.index, "status": t.status,
             "covariance": t.covariance.reshape(-1).tolist()}
            for t in timed
        ],
    }  # fmt: skip
    if tracked:
        document["at_the_end"] = "lost" if tracked[-1].status == "lost" else "found"
    write_text_atomically(sidecar, dumps(document))
    return path, sidecar, len(tracked) - len(timed)
