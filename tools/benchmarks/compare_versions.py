"""Per-scan time of this checkout against another installed version, each in its own process.

    python tools/benchmarks/compare_versions.py --other OTHER_PYTHON [-m adaptive] [--rounds 9]

For a change that must not be slower: install the other version into a virtual environment
of its own (``python -m venv /tmp/old && /tmp/old/bin/pip install .`` in a checkout of it)
and pass that environment's ``python``. Each round runs one child process per version, the
other version first in even rounds and last in odd ones; a child loads the scans, extracts
each once (the other version's kernels compile or load from its cache there, lazy imports
happen), then times
``PASSES`` passes over each dataset and reports the median time per scan. Printed per
method and dataset: the median over rounds of each version's time and the median of the
paired ratios (this / other; below 1 is faster), so that both versions see the same state
of a shared machine.

The datasets: the first 60 scans of the shipped Intel (180 beams) and Freiburg (360 beams)
excerpts, 60 simulated TiM571 scenes (481 beams, seeds 0-59), and 60 rooms seen by a
simulated 1,081-beam scanner (270 deg at 0.25 deg, 1 cm noise, seeded). One method per run
gives the fairest verdict on this 2-core machine; every method given is timed in its own
children. ``--clock cpu`` times the children's processor time instead of wall time (on a busy
machine wall time is mostly waiting). Only the public API of both versions is used. Speed is
measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

PASSES = 7

CHILD = r"""
import json, math, sys, time
import numpy as np
from scanlines import Extractor, Scan
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.sim import random_scene

SCANS = 60


def rooms(count):
    rng = np.random.default_rng(11)
    bearings = np.radians(-135.0 + 0.25 * np.arange(1081))
    cos, sin = np.cos(bearings), np.sin(bearings)
    out = []
    for _ in range(count):
        half_x, half_y = rng.uniform(2.0, 8.0, 2)
        cx, cy = rng.uniform(-1.0, 1.0, 2)
        with np.errstate(divide="ignore"):
            tx = np.where(cos > 0, half_x - cx, -half_x - cx) / cos
            ty = np.where(sin > 0, half_y - cy, -half_y - cy) / sin
        ranges = np.minimum(np.where(tx > 0, tx, np.inf), np.where(ty > 0, ty, np.inf))
        box = slice(int(rng.integers(100, 800)), None)
        box = slice(box.start, box.start + int(rng.integers(20, 120)))
        ranges[box] = np.minimum(ranges[box], rng.uniform(1.0, 3.0))
        ranges = ranges + rng.normal(0.0, 0.01, ranges.shape)
        out.append(Scan(ranges, bearings[0], math.radians(0.25), range_max=30.0))
    return out


def plain(scan):
    return Scan(scan.ranges, scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max)


method, passes = sys.argv[1], int(sys.argv[2])
clock = time.process_time if sys.argv[3] == "cpu" else time.perf_counter
datasets = {
    "intel": [plain(s) for s in list(open_log(sample("intel")))[:SCANS]],
    "freiburg": [plain(s) for s in list(open_log(sample("freiburg")))[:SCANS]],
    "tim571": [plain(random_scene(seed, "tim571").scan(seed).scan) for seed in range(SCANS)],
    "1081 beams": rooms(SCANS),
}
extractor = Extractor(method)
for scans in datasets.values():
    for scan in scans:
        extractor(scan)
result = {}
for name, scans in datasets.items():
    times = []
    for _ in range(passes):
        start = clock()
        for scan in scans:
            extractor(scan)
        times.append((clock() - start) / len(scans))
    result[name] = sorted(times)[len(times) // 2]
print(json.dumps(result))
"""


def child(python: str, method: str, clock: str = "wall") -> dict[str, float]:
    """Seconds per scan of each dataset, measured in a fresh process of ``python``."""
    done = subprocess.run(
        [python, "-c", CHILD, method, str(PASSES), clock],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--other", required=True, help="python of the other version's venv")
    parser.add_argument("-m", "--method", action="append", help="method, repeatable")
    parser.add_argument("--rounds", type=int, default=9, help="alternating process pairs")
    parser.add_argument(
        "--clock", choices=("wall", "cpu"), default="wall", help="cpu: processor time of a child"
    )
    args = parser.parse_args()
    methods = args.method or ["adaptive", "iepf", "pdbs", "split_merge", "partition"]
    print(f"{'method/data':26s} {'other us':>9s} {'this us':>9s} {'paired ratio':>13s}")
    for method in methods:
        old, new = [], []
        for round_ in range(args.rounds):  # ABBA: a drift of the machine's load cancels
            if round_ % 2 == 0:
                old.append(child(args.other, method, args.clock))
                new.append(child(sys.executable, method, args.clock))
            else:
                new.append(child(sys.executable, method, args.clock))
                old.append(child(args.other, method, args.clock))
        for data in old[0]:
            ratio = statistics.median(b[data] / a[data] for a, b in zip(old, new, strict=True))
            print(
                f"{method + '/' + data:26s} {1e6 * statistics.median(a[data] for a in old):9.1f} "
                f"{1e6 * statistics.median(b[data] for b in new):9.1f} {ratio:13.3f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
