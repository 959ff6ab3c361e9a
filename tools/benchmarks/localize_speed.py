"""What `localize`'s global search costs a tracked log: per scan, best of a few runs.

    taskset -c 0 python tools/benchmarks/localize_speed.py LOG --map MAP.json \
        --initial-pose T,X,Y,YAW [--repeats 7]

The log's scans are read once into memory (from the initial time on). Three runs each
repeat: the filter alone (:class:`~scanlines.map.filter.LineMapFilter` stepped scan by
scan, what ``localize`` did before it searched), ``localize`` with the search never entered
(``SearchSettings(lost_after=10**9)``: only the per-scan test of being lost), and
``localize`` as it runs (searching while lost). Prints the best time per scan of each.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from scanlines.geometry.poses import relative_pose
from scanlines.io import open_log
from scanlines.map.filter import LineMapFilter
from scanlines.map.localize import localize, read_line_map
from scanlines.map.relocalise import SearchSettings


def filter_alone(scans, lines, frame, pose) -> int:
    tracker = LineMapFilter(lines)
    tracker.start(frame.pose(pose))
    last = None
    for _, scan in scans:
        increment = None if last is None else relative_pose(last, scan.pose)
        tracker.step(scan.points[scan.valid].astype(np.float64), increment)
        last = scan.pose
    return len(scans)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log")
    parser.add_argument("--map", required=True)
    parser.add_argument("--initial-pose", required=True)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    t0, x, y, yaw = (float(v) for v in args.initial_pose.split(","))
    lines, frame = read_line_map(args.map)
    with open_log(args.log) as reader:
        scans = [(i, s) for i, s in reader.enumerate() if s.pose is not None]
    scans = [(i, s) for i, s in scans if s.timestamp is None or s.timestamp >= t0 - 0.01]
    initial = (t0, (x, y, yaw))
    never = SearchSettings(lost_after=10**9)
    runs = {
        "filter alone": lambda: filter_alone(scans, lines, frame, (x, y, yaw)),
        "search never entered": lambda: len(
            localize(iter(scans), lines, frame, initial, search=never).tracked
        ),
        "as it runs": lambda: len(localize(iter(scans), lines, frame, initial).tracked),
    }
    best: dict[str, float] = {}
    for _ in range(args.repeats):
        for name, run in runs.items():
            started = time.perf_counter()
            count = run()
            per_scan = (time.perf_counter() - started) / count
            best[name] = min(best.get(name, float("inf")), per_scan)
    for name, seconds in best.items():
        print(f"{name}: {1e6 * seconds:.1f} us per scan ({1 / seconds:.0f} scans/s)")


if __name__ == "__main__":
    main()
