"""Record every method's features, or check that this checkout gives the recorded ones bit for bit.

    python tools/benchmarks/same_features.py record features.pkl [-n 300]   # with the old version
    python tools/benchmarks/same_features.py compare features.pkl            # with the new one

For a change that must not change any result (a re-housing, a speed-up): record with the
version before the change (run this file with that version's Python), then compare with
the version after. The scans: ``n`` seeded simulated scenes of every sensor preset (seed
0, the scenes ``scanlines eval -n N --seed 0`` scores) and both shipped excerpts. The
configurations: every registered method with its defaults, and the paper preset. Every
array of every extraction must be equal (NaN equal to NaN); ``compare`` lists the scans
and fields that differ and exits 1 if any does.
"""

from __future__ import annotations

import argparse
import pickle
import sys

import numpy as np

from scanlines import Extractor
from scanlines.data import sample
from scanlines.io import open_log

FIELDS = ("first", "last", "n_points", "lines", "covariances", "breakpoints", "corners", "outliers")
METHODS = ("adaptive", "iepf", "pdbs", "split_merge", "line_tracking", "line_regression")
METHODS += ("ransac", "hough", "partition")


def scans(n: int, real: int | None) -> list:
    """``(key, scan)`` of the simulated scenes and the first ``real`` scans (all: ``None``)
    of each shipped excerpt."""
    try:
        from scanlines.evaluation.scenes import iter_scenes
    except ImportError:  # the layout before the evaluation package
        from scanlines.evaluate import iter_scenes
    out = [(f"{case.sensor}:{case.index}", case.scan) for case in iter_scenes(None, n, 0)]
    for name in ("intel", "freiburg"):
        excerpt = list(open_log(sample(name)))[:real]
        out += [(f"{name}:{i}", scan) for i, scan in enumerate(excerpt)]
    return out


def features(items: list) -> dict:
    """Every configuration's arrays, per scan key."""
    configs = [(method, None) for method in METHODS] + [("adaptive", "paper")]
    result = {}
    for method, preset in configs:
        extractor = Extractor(method, preset)
        result[(method, preset)] = {
            key: tuple(np.asarray(getattr(extractor(scan), f)).copy() for f in FIELDS)
            for key, scan in items
        }
        print(f"{method}:{preset} done", file=sys.stderr, flush=True)
    return result


def differences(recorded: dict, current: dict) -> list[tuple[str, str, str]]:
    """``(configuration, scan, field)`` of every array that is not equal."""
    out = []
    for config, per_scan in recorded.items():
        for key, arrays in per_scan.items():
            for field, old, new in zip(FIELDS, arrays, current[config][key], strict=True):
                if old.shape != new.shape or not np.array_equal(old, new, equal_nan=True):
                    out.append((f"{config[0]}:{config[1]}", key, field))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("record", "compare"))
    parser.add_argument("path")
    parser.add_argument("-n", type=int, default=300, help="scenes per sensor preset (record)")
    parser.add_argument("--real", type=int, help="scans of each excerpt (record; default all)")
    args = parser.parse_args()
    if args.action == "record":
        items = scans(args.n, args.real)
        with open(args.path, "wb") as handle:
            pickle.dump({"n": args.n, "real": args.real, "features": features(items)}, handle)
        print(f"recorded {len(items)} scans x {len(METHODS) + 1} configurations")
        return
    with open(args.path, "rb") as handle:
        recorded = pickle.load(handle)
    items = scans(recorded["n"], recorded.get("real"))
    found = differences(recorded["features"], features(items))
    configurations = len(recorded["features"])
    print(f"{len(found)} differences in {len(items)} scans x {configurations} configurations")
    for row in found[:20]:
        print("  ", *row)
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
