"""Record every configuration's features, or check that this checkout gives the recorded ones.

    python tools/benchmarks/same_features.py record features.npz [-n 300] [--real N]
    python tools/benchmarks/same_features.py compare features.npz

For a change that must not change any result (a port of the kernels, a re-housing, a
speed-up): record with the version before the change, then compare with the version after.
``tests/records/features.npz`` is such a record, small enough to commit (``-n 8 --real
15``), and ``tests/test_same_features.py`` compares against it on every test run.

The scans: ``n`` seeded simulated scenes of every sensor preset (seed 0, the scenes
``scanlines eval -n N --seed 0`` scores), full-circle rooms with and without gaps, a few
degenerate scans, and the first ``real`` scans of each shipped excerpt (Intel, Freiburg,
URG). The configurations (:func:`configurations`): every method with its defaults and
each preset; on the simulated scans also every clustering rule of the
sequential methods, the adaptive method's alternative steps one at a time and fixed noise
overrides; every method and preset again
with each excerpt's sensor profile (:func:`scanlines.sensor.profile.estimate_profile`),
and through :meth:`scanlines.Extractor.batch` on each excerpt as one stack. Every array
of every extraction (segments, lines, covariances, end kinds, breakpoints, corners,
outliers) and each profile's noise line must be equal, NaN equal to NaN; ``compare``
lists the configurations, scans and fields that differ and exits 1 if any does.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterator
from typing import Any

import numpy as np

from scanlines import Extractor, Scan, method_info, method_names
from scanlines.data import sample
from scanlines.evaluation.scenes import iter_scenes
from scanlines.io import open_log
from scanlines.sensor.profile import estimate_profile

FIELDS = ("first", "last", "n_points", "lines", "covariances", "end_kinds")
FIELDS += ("breakpoints", "corners", "outliers")
EXCERPTS = ("intel", "freiburg", "urg")
RULES = ("paper", "abd", "pdbs", "fixed")
VARIANT_SETS = ("simulated",)
"""The sets a configuration other than a method's defaults and presets runs on."""

ADAPTIVE_VARIANTS: tuple[dict[str, Any], ...] = (
    {"denoise": "paper"},
    {"denoise": "none"},
    {"corner_score": "dk"},
    {"corner_score": "dk_signed"},
    {"criterion": "sse"},
    {"fit": "paper"},
    {"corner_split": "shared"},
    {"merge": False},
    {"max_residual": None},
    {"corner_check": False},
    {"noise_model": "constant"},
    {"noise_sigma": 0.01},
    {"range_sigma": 0.01},
    {"dkth_range": (0.0, 0.05)},
    {"slope_window": 4},
)
PARTITION_VARIANTS: tuple[dict[str, Any], ...] = (
    {"noise_sigma": 0.01},
    {"range_sigma": 0.01},
    {"min_length": 0.3, "min_points": 6},
)


def configurations() -> list[tuple[str, str, str | None, dict[str, Any]]]:
    """``(name, method, preset, params)`` of every configuration compared."""
    out = []
    for method in method_names():
        info = method_info(method)
        for preset in (None, *info.presets):
            out.append((f"{method}:{preset or ''}", method, preset, {}))
        if "breakpoints" in info.params:
            for rule in RULES:
                if rule != info.params["breakpoints"].default:
                    out.append(
                        (f"{method}:breakpoints={rule}", method, None, {"breakpoints": rule})
                    )
    variants = [("adaptive", v) for v in ADAPTIVE_VARIANTS]
    variants += [("partition", v) for v in PARTITION_VARIANTS]
    for method, params in variants:
        name = ",".join(f"{k}={v}" for k, v in params.items())
        out.append((f"{method}:{name}", method, None, params))
    return out


def full_circle_scans(count: int) -> Iterator[tuple[str, Scan]]:
    """Rooms seen over a full turn at 1 deg: closed rings, and rings with a gap."""
    rng = np.random.default_rng(7)
    bearings = np.arange(360) * math.radians(1.0)
    cos, sin = np.cos(bearings), np.sin(bearings)
    for k in range(count):
        half_x, half_y = rng.uniform(2.0, 6.0, 2)
        cx, cy = rng.uniform(-1.0, 1.0, 2)
        with np.errstate(divide="ignore"):
            tx = np.where(cos > 0, half_x - cx, -half_x - cx) / cos
            ty = np.where(sin > 0, half_y - cy, -half_y - cy) / sin
        ranges = np.minimum(np.where(tx > 0, tx, np.inf), np.where(ty > 0, ty, np.inf))
        ranges += rng.normal(0.0, 0.01, ranges.shape)
        if k % 2:
            start = int(rng.integers(0, 360))
            ranges[np.arange(start, start + 5) % 360] = 0.0
        yield f"ring:{k}", Scan(ranges, -math.pi + 0.3 * k, math.radians(1.0), range_max=30.0)


def degenerate_scans() -> Iterator[tuple[str, Scan]]:
    """Scans with no, one, two or only scattered returns."""
    step = math.radians(1.0)
    yield "none", Scan(np.zeros(90), 0.0, step)
    yield "one", Scan(np.r_[np.zeros(40), 2.0, np.zeros(40)], 0.0, step)
    yield "two", Scan(np.r_[np.zeros(40), 2.0, 2.01, np.zeros(40)], 0.0, step)
    yield "sparse", Scan(np.tile([2.0, 0.0, 0.0], 30), 0.0, step)
    yield "few", Scan(np.array([1.0, 1.0, 1.0, 1.0]), -0.1, 0.05)


def scans(n: int, real: int | None) -> dict[str, list[tuple[str, Scan]]]:
    """The scans by set: ``simulated`` (with the synthetic ones) and each excerpt's first
    ``real`` scans (all: ``None``)."""
    out = {"simulated": [(f"{c.sensor}:{c.index}", c.scan) for c in iter_scenes(None, n, 0)]}
    out["simulated"] += [*full_circle_scans(6), *degenerate_scans()]
    for name in EXCERPTS:
        excerpt = list(open_log(sample(name)))[:real]
        out[name] = [(f"{name}:{i}", scan) for i, scan in enumerate(excerpt)]
    return out


def _pack(record: dict[str, np.ndarray], prefix: str, arrays: list[tuple]) -> None:
    """Each field of many extractions as one flat array and the rows of each."""
    for k, field in enumerate(FIELDS):
        parts = [np.asarray(values[k]) for values in arrays]
        record[f"{prefix}|{field}|rows"] = np.array([len(p) for p in parts], dtype=np.int64)
        record[f"{prefix}|{field}"] = np.concatenate([p.ravel() for p in parts]) if parts else []


def _arrays(extraction: Any) -> tuple:
    return tuple(np.asarray(getattr(extraction, field)) for field in FIELDS)


def features(sets: dict[str, list[tuple[str, Scan]]], log: Any = None) -> dict[str, np.ndarray]:
    """Every configuration's features of every scan, packed (:func:`_pack`)."""
    record: dict[str, np.ndarray] = {}
    profiles = {}
    for name in EXCERPTS:
        profile = estimate_profile([scan for _, scan in sets[name]], source=name)
        profiles[name] = profile
        record[f"profile|{name}"] = np.array(tuple(profile.noise), dtype=np.float64)
    for label, method, preset, params in configurations():
        extractor = Extractor(method, preset, **params)
        for set_name, items in sets.items():
            if params and set_name not in VARIANT_SETS:
                continue
            _pack(record, f"{label}|{set_name}", [_arrays(extractor(s)) for _, s in items])
        if not params:
            for name in EXCERPTS:
                items = sets[name]
                profiled = Extractor(method, preset, sensor_profile=profiles[name])
                arrays = [_arrays(profiled(s)) for _, s in items]
                _pack(record, f"{label}|{name}|profile", arrays)
                _pack(record, f"{label}|{name}|batch", _batch(extractor, items))
        if log:
            print(f"{label} done", file=log, flush=True)
    return record


def _batch(extractor: Extractor, items: list[tuple[str, Scan]]) -> list[tuple]:
    """The rows of :meth:`Extractor.batch` over the scans as one stack."""
    if not items:
        return []
    first = items[0][1]
    stack = np.stack([scan.ranges for _, scan in items])
    table = extractor.batch(
        stack, first.angle_min, first.angle_increment, first.range_min, first.range_max
    )
    return [_arrays(row) for row in table]


def differences(recorded: dict[str, np.ndarray], current: dict[str, np.ndarray]) -> list[str]:
    """The keys whose arrays are not equal (NaN equal to NaN), or missing on either side."""
    out = sorted(set(recorded) ^ set(current))
    for key in sorted(set(recorded) & set(current)):
        old, new = recorded[key], current[key]
        if old.shape != new.shape or not np.array_equal(old, new, equal_nan=True):
            out.append(key)
    return out


def first_difference(recorded: dict, current: dict, key: str, sets: dict) -> str:
    """Which scan of ``key``'s configuration and set differs first, and how."""
    base, _, suffix = key.rpartition("|")
    field_key = key if suffix != "rows" else base
    parts = field_key.split("|")
    if len(parts) < 3 or field_key not in recorded or field_key not in current:
        return key
    rows_old, rows_new = recorded[f"{field_key}|rows"], current[f"{field_key}|rows"]
    set_name = parts[1]
    width = max(1, recorded[field_key].size // max(int(rows_old.sum()), 1))
    at_old = np.r_[0, np.cumsum(rows_old)] * width
    at_new = np.r_[0, np.cumsum(rows_new)] * width
    for i in range(min(len(rows_old), len(rows_new))):
        old = recorded[field_key][at_old[i] : at_old[i + 1]]
        new = current[field_key][at_new[i] : at_new[i + 1]]
        if old.shape != new.shape or not np.array_equal(old, new, equal_nan=True):
            scan = sets[set_name][i][0] if set_name in sets else i
            return f"{key}: scan {scan}: {old[:8]} != {new[:8]}"
    return key


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("record", "compare"))
    parser.add_argument("path")
    parser.add_argument("-n", type=int, default=300, help="scenes per sensor preset (record)")
    parser.add_argument("--real", type=int, help="scans of each excerpt (record; default all)")
    args = parser.parse_args()
    if args.action == "record":
        sets = scans(args.n, args.real)
        record = features(sets, log=sys.stderr)
        record["meta|n"] = np.array(args.n)
        record["meta|real"] = np.array(-1 if args.real is None else args.real)
        np.savez_compressed(args.path, **record)
        print(f"recorded {sum(map(len, sets.values()))} scans, {len(configurations())} configs")
        return
    with np.load(args.path) as stored:
        recorded = dict(stored)
    real = int(recorded.pop("meta|real"))
    sets = scans(int(recorded.pop("meta|n")), None if real < 0 else real)
    current = features(sets)
    found = differences(recorded, current)
    print(f"{len(found)} arrays differ of {len(recorded)}")
    for key in found[:20]:
        print("  ", first_difference(recorded, current, key, sets))
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
