"""The strict repeatability of methods on every shared real log, in both modes: one table.

    python tools/benchmarks/real_table.py DATA [-m partition -m adaptive -m iepf]
        [--modes profiled bare] [--logs intel fr079-raw ...] [--pairs 200] [--jobs 2]
        [--out table.md] [--results DIR] [--cache DIR]

``DATA`` is the shared data folder (``intel-research-lab/``, ``freiburg-079/``,
``hokuyo-urg04lx-mines/``, ``sick-lms511-bench/``, ``sick-lms111-bench/``); a log not found
there is left out, with a note. Each (log, mode) is one ``scanlines eval --real LOG
--pairs N [--bare]``: each log's pairs are registered once
(:func:`~scanlines.evaluation.repeatability.register_pairs`; with ``--cache DIR`` kept
there for the next run, since they do not depend on the methods) and scored in each mode
(:func:`~scanlines.evaluation.repeatability.repeatability_of_scans`); the logs run in
``--jobs`` processes, the longest first. A log that fails is reported in its rows and the
others go on (exit code 1 at the end). Progress goes to stderr, one line per log and mode.

The table (markdown, to ``--out`` or stdout): one row per log and mode, one column per
method spec, each cell ``strict repeatability / coverage / repeated m per scan / fidelity
mm``; the row also gives the pairs scored. ``--results DIR`` also writes every run's
``repeatability.csv``, ``repeatability_pairs.csv`` and ``.json`` into ``DIR/LOG-MODE/``.
Method specs are those of ``scanlines eval -m`` (``'partition?penalty=30@p30'``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

LOGS: dict[str, tuple[str, str]] = {
    "intel": ("Intel corrected", "intel-research-lab/original/intel-corrected.log.gz"),
    "fr079-corrected": (
        "Freiburg 079 corrected",
        "freiburg-079/original/freiburg-079-corrected.log.gz",
    ),
    "fr079-raw": ("Freiburg 079 raw", "freiburg-079/original/fr079.log.gz"),
    "urg-exp1": ("URG-04LX exp1", "hokuyo-urg04lx-mines/original/exp1.dat.gz"),
    "urg-exp2": ("URG-04LX exp2", "hokuyo-urg04lx-mines/original/exp2.dat.gz"),
    "lms511-0301": ("LMS511 bench 0301", "sick-lms511-bench/derived/20210301_lms511.npz"),
    "lms511-0302": ("LMS511 bench 0302", "sick-lms511-bench/derived/20210302_lms511.npz"),
    "lms111": ("LMS111 bench", "sick-lms111-bench/derived/20210302_lms111.npz"),
    "fr079-sm": ("Freiburg 079 raw, scan-matched poses", "freiburg-079/original/fr079-sm.log.gz"),
}
"""Short name: (row label, path under the data folder). ``fr079-sm`` is not run unless
named: its ranges are the raw log's and ICP takes its poses to the same pairs, so its
figures are the raw log's."""

DEFAULT_LOGS = [name for name in LOGS if name != "fr079-sm"]

COST = {"lms511-0302": 6, "lms511-0301": 5, "fr079-corrected": 4, "fr079-raw": 4, "intel": 3}
"""Rough relative run time, to start the long runs first (1 for the rest)."""


def registered_pairs(path: str, scans, tol, cache: str):
    """:func:`register_pairs` of ``scans``, kept in ``cache`` (when given) under a name
    of the log and everything the registration depends on."""
    import hashlib
    import pickle

    from scanlines.evaluation.repeatability import register_pairs
    from scanlines.geometry.registration import IcpSettings

    if not cache:
        return register_pairs(scans, tol)
    key = repr((Path(path).resolve(), Path(path).stat().st_size, len(scans), tol, IcpSettings()))
    file = Path(cache) / f"{Path(path).name}-{hashlib.sha256(key.encode()).hexdigest()[:16]}.pkl"
    if file.exists():
        return pickle.loads(file.read_bytes())
    registered = register_pairs(scans, tol)
    file.parent.mkdir(parents=True, exist_ok=True)
    file.write_bytes(pickle.dumps(registered))
    return registered


def measure(
    name: str,
    path: str,
    methods: list[str],
    modes: list[str],
    pairs: int,
    scans: int | None,
    out: str,
    cache: str,
) -> list[dict[str, Any]]:
    """One log: the pairs registered once, then per mode the figures of every method (or
    the error)."""
    from itertools import islice

    from scanlines.evaluation.repeatability import (
        RepeatTolerances,
        repeatability_of_scans,
        write_results,
    )
    from scanlines.io import open_log

    rows = []
    label = LOGS[name][0]
    try:
        started = time.perf_counter()
        tol = RepeatTolerances(max_pairs=pairs)
        read = list(islice(open_log(path).enumerate(), scans))
        say(f"{label}: {len(read)} scans read, registering the pairs")
        registered = registered_pairs(path, read, tol, cache)
        used = sum(pair.used for pair in registered[0])
        say(f"{label}: {used} pairs used, {time.perf_counter() - started:.0f} s")
        for mode in modes:
            result = repeatability_of_scans(
                read, methods, log=path, tol=tol, bare=mode == "bare", registered=registered
            )
            if out:
                write_results([result], Path(out) / f"{name}-{mode}")
            rows.append(
                {
                    "name": name,
                    "mode": mode,
                    "seconds": time.perf_counter() - started,
                    "pairs": len(result.used_pairs),
                    "noise": result.noise().split(": ", 1)[1],
                    "cells": {
                        m.spec.label: (m.strict, m.coverage, m.repeated_metres, m.fidelity_mm)
                        for m in result.methods
                    },
                }
            )
            say(f"{label}, {mode}: scored, {time.perf_counter() - started:.0f} s")
    except Exception as error:  # one bad log must not stop the table
        rows += failed(name, modes, {row["mode"] for row in rows}, error)
    return rows


def failed(name: str, modes: list[str], done: set[str], error: BaseException) -> list[dict]:
    text = f"{type(error).__name__}: {error}".replace("|", "/").replace("\n", " ")
    return [{"name": name, "mode": mode, "error": text} for mode in modes if mode not in done]


def say(text: str) -> None:
    print(f"real_table: {text}", file=sys.stderr, flush=True)


def cell(figures: tuple[float, float, float, float]) -> str:
    strict, coverage, metres, fidelity = figures
    return f"{strict:.3f} / {coverage:.2f} / {metres:.2f} / {fidelity:.1f}"


def table(rows: list[dict[str, Any]], labels: list[str], pairs: int) -> str:
    head = ["log", "mode", "noise line", "pairs", *labels]
    lines = [
        f"Strict repeatability / coverage / repeated m per scan / fidelity mm "
        f"(`scanlines eval real LOG --pairs {pairs} [--bare]`).",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for row in rows:
        label = LOGS[row["name"]][0]
        if "error" in row:
            lines.append(f"| {label} | {row['mode']} | | | error: {row['error']} |")
            continue
        figures = [cell(row["cells"][m]) for m in labels]
        head = f"| {label} | {row['mode']} | {row['noise']} | {row['pairs']} | "
        lines.append(head + " | ".join(figures) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("data", type=Path, help="the shared data folder")
    parser.add_argument("-m", "--method", action="append", help="method spec, repeatable")
    parser.add_argument("--modes", nargs="+", default=["profiled", "bare"])
    parser.add_argument("--logs", nargs="+", choices=tuple(LOGS), default=DEFAULT_LOGS)
    parser.add_argument("--pairs", type=int, default=200)
    parser.add_argument("--scans", type=int, default=None, help="the first N scans of a log")
    parser.add_argument("--jobs", "-j", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--out", type=Path, help="write the table here (default: stdout)")
    parser.add_argument("--results", type=Path, help="also write each run's files here")
    parser.add_argument(
        "--cache", type=Path, help="keep each log's registered pairs here, for the next run"
    )
    args = parser.parse_args(argv)
    methods = args.method or ["partition", "adaptive", "iepf"]
    if not set(args.modes) <= {"profiled", "bare"}:
        parser.error("--modes takes profiled and bare")
    from scanlines.evaluation.specs import parse_specs

    labels = [spec.label for spec in parse_specs(methods)]  # bad specs fail here, once
    found = {}
    for name in args.logs:
        path = args.data / LOGS[name][1]
        if path.exists():
            found[name] = path
        else:
            say(f"{path} not found, left out")
    order = sorted(found, key=lambda name: -COST.get(name, 1))
    results: dict[tuple[str, str], dict[str, Any]] = {}
    started = time.perf_counter()
    out, cache = str(args.results or ""), str(args.cache or "")
    with ProcessPoolExecutor(max(1, args.jobs)) as pool:
        futures = {
            pool.submit(
                measure, n, str(found[n]), methods, args.modes, args.pairs, args.scans, out, cache
            ): n
            for n in order
        }
        for done, future in enumerate(as_completed(futures), start=1):
            name = futures[future]
            try:
                rows = future.result()
            except Exception as error:  # the worker itself died
                rows = failed(name, args.modes, set(), error)
            for row in rows:
                results[(name, row["mode"])] = row
            errors = [row["error"] for row in rows if "error" in row]
            say(
                f"[{done}/{len(order)} logs, {time.perf_counter() - started:.0f} s] "
                f"{LOGS[name][0]} " + (f"failed: {errors[0]}" if errors else "done")
            )
    runs = [(name, mode) for name in found for mode in args.modes]
    text = table([results[run] for run in runs], labels, args.pairs)
    if args.out:
        args.out.write_text(text)
        say(f"wrote {args.out}")
    else:
        print(text, end="")
    return 1 if any("error" in row for row in results.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
