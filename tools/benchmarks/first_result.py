"""The first results of a fresh process: ``import scanlines``, then the first call of every
method and preset on a 361-beam scan, each timed.

    python tools/benchmarks/first_result.py [--python OTHER_PYTHON] [--repeats 5]

Each repeat is a new process with empty caches (``XDG_CACHE_HOME`` and ``MPLCONFIGDIR``
pointed at a new folder), so nothing a previous process left is used.
Printed: the median over repeats of the import, of each first call and of the whole (wall
from before the import to after the last call), with the load average. ``--python`` runs
another installed version (its own virtual environment's interpreter) the same way.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

CHILD = r"""
import json, time
started = time.perf_counter()
import scanlines
imported = time.perf_counter()
import numpy as np
bearings = np.radians(np.arange(-90.0, 90.5, 0.5))
across = np.maximum(np.abs(np.sin(bearings)), 1e-9)
ranges = np.minimum(3.0 / np.abs(np.cos(bearings)), 2.0 / across)
scan = scanlines.Scan(ranges, bearings[0], np.radians(0.5), range_max=30.0)
calls = {}
for name in scanlines.method_names():
    for preset in (None, *scanlines.method_info(name).presets):
        before = time.perf_counter()
        scanlines.extract(scan, method=name, preset=preset)
        calls[f"{name}:{preset or ''}"] = time.perf_counter() - before
done = time.perf_counter()
print(json.dumps({"import": imported - started, "calls": calls, "total": done - started}))
"""


def child(python: str) -> dict:
    with tempfile.TemporaryDirectory(prefix="scanlines-first-") as cache:
        env = {
            **os.environ,
            "XDG_CACHE_HOME": cache,
            "MPLCONFIGDIR": os.path.join(cache, "mpl"),
        }
        done = subprocess.run(
            [python, "-c", CHILD], env=env, capture_output=True, text=True, check=True
        )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--python", default=sys.executable, help="the interpreter to time")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    load = os.getloadavg()
    runs = [child(args.python) for _ in range(args.repeats)]
    print(f"load average before: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print(f"import scanlines: {1e3 * statistics.median(r['import'] for r in runs):.1f} ms")
    for name in runs[0]["calls"]:
        seconds = statistics.median(r["calls"][name] for r in runs)
        print(f"first {name:26s} {1e3 * seconds:9.1f} ms")
    total = statistics.median(r["total"] for r in runs)
    print(f"import and every first call, wall: {1e3 * total:.1f} ms (median of {len(runs)})")


if __name__ == "__main__":
    main()
