"""Per-scan time of this checkout against another installed version, in one process.

    python tools/benchmarks/compare_versions.py --other OTHER_SITE_PACKAGES [-m iepf] [--rounds 21]

For a change that must not be slower: install the other version into a virtual
environment of its own (``python -m venv /tmp/old && /tmp/old/bin/pip install .`` in a
checkout of it) and pass that environment's ``site-packages``. Both versions are loaded
into this process (the other one first, its kernels compiled or loaded from its cache and
called once on every scan before this checkout's package takes the name ``scanlines``), and
their passes over the same scans alternate, so that both see the same state of a shared
machine. Printed per method and dataset: the median time of a pass per scan for each
version and the median of the paired ratios (this / other; below 1 is faster).

Only for versions before the settings records: when both versions pass their settings to
the kernels as numpy record arrays (every version since the re-housing, 0589ad8), numba
in this process types the second version's record on every call (``from_struct_dtype``
in a profile), and its calls took 3-4x their time in a process of their own (2026-12-02,
against a7268b7). Compare two such versions in separate processes, interleaved.

Methods are timed in the order given, and on this 2-core machine the one timed first in a
process measures the fairest (later ones showed ratios up to 1.1 either way from the order
alone): time one method per run for a verdict. Only the public API of both versions is
used (``Extractor``, ``Scan``, ``scanlines.data.sample``, ``scanlines.io.open_log``).
Speed is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
import gc
import statistics
import sys
import time
from pathlib import Path

import numpy as np

SCANS = 60
SLOW_METHODS = ("line_tracking", "line_regression", "ransac", "hough")


def load_other(site_packages: str, methods: list[str]) -> tuple[dict, dict]:
    """The other version's extractors and its scans (Intel excerpt, simulated TiM571)."""
    site_packages = str(Path(site_packages).resolve())
    sys.path.insert(0, site_packages)
    from scanlines import Extractor, Scan
    from scanlines.data import sample
    from scanlines.io import open_log
    from scanlines.sim import random_scene

    if not sys.modules["scanlines"].__file__.startswith(site_packages):
        raise SystemExit(f"{site_packages} holds no scanlines package")
    intel = list(open_log(sample("intel")))[:SCANS]
    tim = [random_scene(seed, "tim571").scan(seed).scan for seed in range(SCANS)]
    tim = [Scan(s.ranges, s.angle_min, s.angle_increment, s.range_min, s.range_max) for s in tim]
    extractors = {m: Extractor(m) for m in methods}
    for extractor in extractors.values():  # load every kernel while its modules import
        for scan in intel + tim:
            extractor(scan)
    for name in [k for k in sys.modules if k == "scanlines" or k.startswith("scanlines.")]:
        sys.modules["other_" + name] = sys.modules.pop(name)
    sys.path.remove(site_packages)
    return extractors, {"intel": intel, "tim571": tim}


def per_scan(extractor, scans) -> float:
    start = time.perf_counter()
    for scan in scans:
        extractor(scan)
    return (time.perf_counter() - start) / len(scans)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--other", required=True, help="site-packages of the other version")
    parser.add_argument("-m", "--method", action="append", help="method, repeatable")
    parser.add_argument("--rounds", type=int, default=21, help="alternating passes")
    args = parser.parse_args()
    methods = args.method or ["adaptive", "iepf", "pdbs", "split_merge"]
    others, datasets = load_other(args.other, methods)
    from scanlines import Extractor, Scan

    gc.disable()
    print(f"{'method/data':24s} {'other us':>9s} {'this us':>9s} {'paired ratio':>13s}")
    for method in methods:
        this = Extractor(method)
        for data, other_scans in datasets.items():
            scans = [
                Scan(s.ranges, s.angle_min, s.angle_increment, s.range_min, s.range_max)
                for s in other_scans
            ]
            if method in SLOW_METHODS:
                other_scans, scans = other_scans[:15], scans[:15]
            per_scan(others[method], other_scans), per_scan(this, scans)
            old, new = [], []
            for _ in range(args.rounds):
                old.append(per_scan(others[method], other_scans))
                new.append(per_scan(this, scans))
            ratio = statistics.median(b / a for a, b in zip(old, new, strict=True))
            print(
                f"{method + '/' + data:24s} {1e6 * np.median(old):9.1f} "
                f"{1e6 * np.median(new):9.1f} {ratio:13.3f}"
            )


if __name__ == "__main__":
    main()
