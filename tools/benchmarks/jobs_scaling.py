"""Scans per second of ``Extractor.batch`` and of a whole run with 1 and 2 threads, this
checkout against another installed version, each in its own processes, interleaved.

    python tools/benchmarks/jobs_scaling.py --other OTHER_PYTHON [-m adaptive] [--rounds 3]

The log: the shipped Intel excerpt's records repeated 8 times (2,400 scans), written once
to a temporary folder. ``batch``: ``Extractor.batch`` over the whole stack with
``jobs=1`` and ``jobs=2`` (threads; the kernels release the GIL). ``run``:
``scanlines.runs.runner.run_log_to_file`` to JSON Lines with ``jobs=1`` and ``jobs=2``, reading,
extracting, encoding and writing (one profile measured first, as ``scanlines run`` does).
Printed: the median over rounds of each version's scans per second, and the speed-up of
two jobs over one.
"""

from __future__ import annotations

import argparse
import gzip
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import json, sys, tempfile, time
from pathlib import Path
import numpy as np
from scanlines import Extractor
from scanlines.io import open_log
from scanlines.runs.runner import log_profile, run_log_to_file

method, log = sys.argv[1], Path(sys.argv[2])
scans = list(open_log(log))
stack = np.stack([s.ranges for s in scans])
first = scans[0]
extractor = Extractor(method, sensor_profile=log_profile(log, {}))
extractor(first)
out = {}
for jobs in (1, 2):
    extractor.batch(stack[:50], first.angle_min, first.angle_increment, first.range_min,
                    first.range_max, jobs=jobs)
    start = time.perf_counter()
    extractor.batch(stack, first.angle_min, first.angle_increment, first.range_min,
                    first.range_max, jobs=jobs)
    out[f"batch {jobs}"] = len(scans) / (time.perf_counter() - start)
with tempfile.TemporaryDirectory() as folder:
    for jobs in (1, 2):
        with open_log(log) as reader:
            start = time.perf_counter()
            run_log_to_file(reader, extractor, Path(folder) / f"out{jobs}.jsonl", jobs=jobs,
                            input_name=log.name, overwrite=True)
            out[f"run {jobs}"] = len(scans) / (time.perf_counter() - start)
print(json.dumps(out))
"""


def repeated_log(folder: Path, copies: int = 8) -> Path:
    """The Intel excerpt's lines repeated ``copies`` times, as a gzip CARMEN log."""
    from scanlines.data import sample

    with gzip.open(sample("intel"), "rt") as handle:
        lines = handle.read().splitlines(keepends=True)
    path = folder / "intel_x8.clf.gz"
    with gzip.open(path, "wt") as handle:
        for _ in range(copies):
            handle.writelines(lines)
    return path


def child(python: str, method: str, log: Path) -> dict[str, float]:
    done = subprocess.run(
        [python, "-c", CHILD, method, str(log)], capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--other", required=True, help="python of the other version's venv")
    parser.add_argument("-m", "--method", default="adaptive")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        log = repeated_log(Path(folder))
        old, new = [], []
        for _ in range(args.rounds):
            old.append(child(args.other, args.method, log))
            new.append(child(sys.executable, args.method, log))
    print(f"{args.method}: scans / s, median of {args.rounds} rounds")
    print(f"{'what':10s} {'other':>9s} {'this':>9s}")
    for key in old[0]:
        a, b = statistics.median(r[key] for r in old), statistics.median(r[key] for r in new)
        print(f"{key:10s} {a:9.0f} {b:9.0f}")
    for version, runs in (("other", old), ("this", new)):
        for kind in ("batch", "run"):
            gain = statistics.median(r[f"{kind} 2"] / r[f"{kind} 1"] for r in runs)
            print(f"{version} {kind}: 2 jobs / 1 job = {gain:.2f}")


if __name__ == "__main__":
    main()
