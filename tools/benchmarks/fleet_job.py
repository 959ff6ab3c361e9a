"""The fleet job of docs/SCALE.md: many logs through local processes and a Dask LocalCluster.

    python tools/benchmarks/fleet_job.py --data DATA --work /tmp/fleet [--copies 5] [--jobs 2]

Builds a folder of ``copies`` copies of the shipped excerpts and of the real logs under
``--data`` (Intel raw and corrected, Freiburg 079 raw, scan-matched and corrected, both
URG-04LX runs), the last copy of three of them turned into MCAP bags by ``scanlines run
--out x.mcap``; then, in one run, extracts it into a Parquet dataset with ``jobs`` local
processes and with a Dask ``LocalCluster`` of ``jobs`` workers, alternating, ``--rounds``
times each. Prints wall time, scans per second, the Dask/local ratio, each worker's peak
resident memory, and whether the two datasets' segment rows are equal; then checks every
distinct log's rows against a single-log ``scanlines run`` to JSON Lines.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

REAL_LOGS = (
    "intel-research-lab/derived/intel_raw_first5505.clf.gz",
    "intel-research-lab/original/intel-corrected.log.gz",
    "freiburg-079/original/fr079.log.gz",
    "freiburg-079/original/fr079-sm.log.gz",
    "freiburg-079/original/freiburg-079-corrected.log.gz",
    "hokuyo-urg04lx-mines/original/exp1.dat.gz",
    "hokuyo-urg04lx-mines/original/exp2.dat.gz",
)
AS_MCAP = ("intel-corrected.log.gz", "fr079.log.gz", "exp1.dat.gz")
QUERY = """select log, scan, segment, first, last, rho, alpha, var_rho, start_kind, end_kind
    from read_parquet('{dataset}/segments/*/*.parquet', hive_partitioning = true)"""


def build(data: Path, work: Path, copies: int) -> Path:
    from scanlines.data import sample

    logs = work / "logs"
    if logs.exists():
        return logs
    originals = [sample(name) for name in ("intel", "freiburg", "urg")]
    originals += [data / relative for relative in REAL_LOGS]
    for copy in range(copies):
        folder = logs / f"copy{copy}"
        folder.mkdir(parents=True)
        for original in originals:
            if copy == copies - 1 and original.name in AS_MCAP:
                target = folder / (original.name.split(".")[0] + ".mcap")
                scanlines("run", original, "--out", target)
                target.with_name(target.name + ".meta.json").unlink()
            else:
                shutil.copy(original, folder / original.name)
    return logs


def scanlines(*args: object) -> str:
    out = subprocess.run(
        [sys.executable, "-m", "scanlines", *map(str, args)], capture_output=True, text=True
    )
    if out.returncode not in (0,):
        raise SystemExit(f"scanlines {' '.join(map(str, args))} failed: {out.stderr[-500:]}")
    return out.stdout


def run_once(logs: Path, dataset: Path, jobs: int, scheduler: str | None) -> dict:
    from scanlines.runs.fleet import run_fleet

    shutil.rmtree(dataset, ignore_errors=True)
    started = time.perf_counter()
    summary = run_fleet([logs], dataset, jobs=jobs, scheduler=scheduler)
    seconds = time.perf_counter() - started
    assert not summary.failed, [(o.log, o.reason) for o in summary.failed]
    return {"seconds": seconds, "scans": summary.scans, "engine": summary.engine,
            "peaks": sorted(summary.worker_peak_mb.values())}  # fmt: skip


def rows(dataset: Path) -> list[tuple]:
    import duckdb

    return sorted(duckdb.connect().execute(QUERY.format(dataset=dataset)).fetchall())


def single_log_check(logs: Path, dataset: Path, work: Path) -> str:
    """Each distinct log of copy 0 run alone to JSON Lines; its rows against the dataset's."""
    import duckdb

    con = duckdb.connect()
    checked = 0
    for log in sorted((logs / "copy0").iterdir()):
        out = work / f"single-{log.name}.jsonl"
        out.unlink(missing_ok=True)
        Path(str(out) + ".meta.json").unlink(missing_ok=True)
        scanlines("run", log, "--out", out)
        expected = [
            (record["scan"], k, s["first"], s["last"], s["rho"], s["alpha"])
            for record in map(json.loads, out.read_text().splitlines())
            for k, s in enumerate(record["segments"])
        ]
        got = con.execute(
            f"select scan, segment, first, last, rho, alpha from read_parquet("
            f"'{dataset}/segments/log=copy0__{log.name}/*.parquet') order by scan, segment"
        ).fetchall()
        if got != expected:
            return f"DIFFERENT for {log.name}"
        checked += 1
    return f"equal for all {checked} distinct logs"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--copies", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    logs = build(args.data, args.work, args.copies)
    print(f"logs: {sum(1 for _ in logs.glob('*/*'))} in {logs}", flush=True)
    times: dict[str, list[float]] = {"local": [], "dask": []}
    for _ in range(args.rounds):
        for name, scheduler in (("local", None), ("dask", "local")):
            result = run_once(logs, args.work / f"dataset-{name}", args.jobs, scheduler)
            times[name].append(result["seconds"])
            print(f"{result['engine']}: {result['scans']} scans in {result['seconds']:.1f} s "
                  f"({result['scans'] / result['seconds']:.0f} scans/s); worker peaks "
                  f"{', '.join(f'{p:.0f}' for p in result['peaks'])} MB", flush=True)  # fmt: skip
    local, dask = statistics.median(times["local"]), statistics.median(times["dask"])
    print(f"median: local {local:.1f} s, Dask {dask:.1f} s, Dask / local {dask / local:.2f}")
    same = rows(args.work / "dataset-local") == rows(args.work / "dataset-dask")
    print(f"segment rows, local against Dask: {'equal' if same else 'DIFFERENT'}")
    print("against single-log runs:", single_log_check(logs, args.work / "dataset-dask", args.work))


if __name__ == "__main__":
    main()
