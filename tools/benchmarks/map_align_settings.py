"""``map --align``'s ATE on a raw log for given filter settings, in one process.

    python tools/benchmarks/map_align_settings.py RAW REFERENCE '{"gate_min": 0.15}' [SCANS]

Builds the map of RAW (its first SCANS scans) tracking with ``FilterSettings(**JSON)`` and
prints the ATE and the RPE per metre of the tracked poses against REFERENCE (a log with
corrected poses or a TUM file), as ``scanlines eval --trajectory`` scores them.
"""

from __future__ import annotations

import json
import sys
import time
from itertools import islice

import numpy as np

from scanlines.evaluation.trajectory import Trajectory, load_trajectory, trajectory_error
from scanlines.io import open_log
from scanlines.map import build_map
from scanlines.map.filter import FilterSettings


def main() -> None:
    raw, reference, settings = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    limit = int(sys.argv[4]) if len(sys.argv) > 4 else None
    started = time.perf_counter()
    with open_log(raw) as reader:
        build = build_map(islice(reader.enumerate(), limit), track=FilterSettings(**settings))
    timed = [t for t in build.tracked if t.timestamp is not None]
    times = np.array([t.timestamp for t in timed])
    poses = np.array([build.frame.world_pose(t.pose) for t in timed])
    order = np.argsort(times, kind="stable")
    estimate = Trajectory(times[order], poses[order], raw)
    ref = load_trajectory(reference)
    keep = ref.times <= estimate.times[-1]
    score = trajectory_error(estimate, Trajectory(ref.times[keep], ref.poses[keep], reference))
    seconds = time.perf_counter() - started
    print(f"{settings}: ATE {score.ate_rmse:.4f} m, RPE per metre {score.rpe_rmse:.4f} m, "
          f"{build.not_aligned} scans did not fit, {seconds:.0f} s")  # fmt: skip


if __name__ == "__main__":
    main()
