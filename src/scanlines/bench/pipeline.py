"""What a user feels besides one kernel call: ``scanlines bench``'s pipeline section.

* **Cold start**: a fresh process imports scanlines and makes its first extraction with
  the method (the kernels are compiled at install: nothing compiles here), then its first
  with every other method; timed inside the child, import and first calls apart.
* **Stages of** ``scanlines run`` **on a log**, per scan: reading and parsing the log,
  extraction of whole chunks (:meth:`~scanlines.Extractor.batch`), the single-call loop
  on the same scans, encoding each text format, and end to end (read, extract, write,
  commit) into JSON Lines, CSV and MCAP.
* **Jobs**: end to end to JSON Lines with 1 to ``max_jobs`` threads, on a log of many
  chunks (a text log's records repeated :data:`JOBS_COPIES` times: the 300-scan excerpt
  alone makes two chunks, which two threads cannot share out), with the machine's
  load average before and after (the machine may be shared) and the cores other processes
  kept busy during a second of sleep just before (the load average also counts this
  process's own work of the minutes before).
* **The floor**: one numpy pass over the returns of the same stack (the sum of their
  ``x`` and ``y``), against which the extraction's cost per scan is a ratio.

Every figure of one section is measured in the same process, close in time, so that the
ratios hold on a shared machine even where the absolute times do not.
"""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.bench.machine import cores_busy
from scanlines.builtin_methods import DEFAULT_METHOD
from scanlines.report import TableData
from scanlines.runs.runner import CHUNK_SCANS

__all__ = ["ColdStart", "PipelineResult", "cold_start", "measure_pipeline", "one_pass"]

_CHILD = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np
from scanlines import Extractor, Scan, method_names
t1 = time.perf_counter()
bearings = np.radians(np.arange(-90.0, 90.5, 0.5))
scan = Scan(np.minimum(3.0 / np.abs(np.cos(bearings)), 2.0 / np.abs(np.sin(bearings))),
            bearings[0], np.radians(0.5), range_max=30.0)
Extractor(sys.argv[1])(scan)
t2 = time.perf_counter()
for name in method_names():
    Extractor(name)(scan)
t3 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "first_call_s": t2 - t1, "every_method_s": t3 - t2}))
"""


@dataclass
class ColdStart:
    """Seconds to import scanlines, to make the first extraction of ``method`` (a 361-beam
    scan) in a fresh process, and then the first of every method."""

    method: str
    import_s: float
    first_call_s: float
    every_method_s: float


def cold_start(method: str = DEFAULT_METHOD) -> ColdStart:
    """:class:`ColdStart` of ``method``, measured in a child process."""
    done = subprocess.run(
        [sys.executable, "-c", _CHILD, method], capture_output=True, text=True, check=True
    )
    timings = json.loads(done.stdout.strip().splitlines()[-1])
    return ColdStart(method, **timings)


def one_pass(stack, valid, cos, sin):
    """The floor: one numpy pass over the returns of each row (the sums of their x and
    y)."""
    ranges = np.where(valid, stack, 0.0)
    return np.stack((ranges @ cos, ranges @ sin), axis=1)


JOBS_COPIES = 8
"""Times the jobs section repeats a text log's records (:func:`_repeated_log`)."""


@dataclass
class PipelineResult:
    """The figures of the section (see the module docstring); times in microseconds per
    scan, throughputs in scans per second."""

    log: str
    scans: int
    method: str
    stages_us: dict[str, float] = field(default_factory=dict)
    end_to_end: dict[str, float] = field(default_factory=dict)
    jobs: dict[int, float] = field(default_factory=dict)
    jobs_scans: int = 0
    load_before: list[float] = field(default_factory=list)
    load_after: list[float] = field(default_factory=list)
    other_cores_busy: float | None = None
    floor_us: float = 0.0
    cold: ColdStart | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def tables(self) -> list[TableData]:
        stage_rows = [(name, f"{us:,.1f}") for name, us in self.stages_us.items()]
        batch, loop = self.stages_us.get("extract (batch)"), self.stages_us.get("extract (loop)")
        if batch and loop:
            stage_rows.append(("loop / batch", f"{loop / batch:.2f}x"))
        if self.floor_us:
            stage_rows.append(("one pass over the returns (floor)", f"{self.floor_us:.2f}"))
            stage_rows.append(("batch / floor", f"{batch / self.floor_us:,.0f}x"))
        tables = [
            TableData(
                f"run stages, {self.method} on {self.log} ({self.scans} scans), us / scan",
                ("stage", "us / scan"),
                tuple(stage_rows),
            ),
            TableData(
                "run end to end, one job",
                ("output", "scans / s"),
                tuple((name, f"{rate:,.0f}") for name, rate in self.end_to_end.items()),
            ),
        ]
        if self.jobs:
            one = self.jobs.get(1)
            load = f"load average before {self.load_before[0]:.2f}, after {self.load_after[0]:.2f}"
            if self.other_cores_busy is not None:
                load += f"; other processes just before: {self.other_cores_busy:.2f} cores busy"
            chunks = -(-self.jobs_scans // CHUNK_SCANS)
            size = f"{self.jobs_scans:,} scans, {chunks} chunks"
            tables.append(
                TableData(
                    f"run to JSON Lines by jobs ({size}; {load}; {os.cpu_count()} cores)",
                    ("jobs", "scans / s", "speed-up"),
                    tuple(
                        (str(j), f"{rate:,.0f}", f"{rate / one:.2f}x" if one else "-")
                        for j, rate in self.jobs.items()
                    ),
                )
            )
        if self.cold is not None:
            c = self.cold
            tables.append(
                TableData(
                    f"cold start of {c.method} in a fresh process",
                    ("what", "ms"),
                    (
                        ("import scanlines", f"{1e3 * c.import_s:.1f}"),
                        (
                            f"first extraction ({c.method}, 361 beams)",
                            f"{1e3 * c.first_call_s:.1f}",
                        ),
                        ("then the first of every method", f"{1e3 * c.every_method_s:.1f}"),
                    ),
                )
            )
        return tables


def measure_pipeline(
    log: str | Path,
    *,
    method: str = DEFAULT_METHOD,
    repeats: int = 3,
    max_jobs: int = 1,
    max_scans: int | None = None,
    with_cold_start: bool = False,
    tick: Callable[[str], None] = lambda _stage: None,
) -> PipelineResult:
    """Measure the section on the first ``max_scans`` scans of ``log`` (all by default;
    see the module docstring)."""
    from scanlines import Extractor
    from scanlines.io import open_log
    from scanlines.runs.runner import log_profile

    log = Path(log)
    extractor = Extractor(method, sensor_profile=log_profile(log, {}))
    with open_log(log) as reader:
        scans = list(itertools.islice(reader, max_scans))
    selection = slice(0, len(scans))
    result = PipelineResult(log.name, len(scans), method)
    per_scan = 1e6 / max(1, len(scans))

    def best(work: Callable[[], Any]) -> float:
        work()  # untimed
        return min(_seconds(work) for _ in range(repeats)) * per_scan

    result.stages_us["read and parse"] = best(lambda: _read(log, len(scans)))
    stacks = _stacks(scans)
    result.stages_us["extract (batch)"] = best(lambda: [extractor.batch(*s) for s in stacks])
    if max_jobs > 1:
        result.stages_us[f"extract (batch, {max_jobs} threads)"] = best(
            lambda: [extractor.batch(*s, jobs=max_jobs) for s in stacks]
        )
    result.stages_us["extract (loop)"] = best(lambda: [extractor(scan) for scan in scans])
    tables = [extractor.batch(*s) for s in stacks]
    for name, suffix in (("encode JSON Lines", ".jsonl"), ("encode CSV", ".csv")):
        result.stages_us[name] = best(lambda suffix=suffix: _encode_all(scans, tables, suffix))
    tick("run stages")
    for suffix in (".jsonl", ".csv", ".mcap"):
        _run_seconds(log, selection, extractor, suffix, 1)  # untimed: imports, first writes
        seconds = min(_run_seconds(log, selection, extractor, suffix, 1) for _ in range(repeats))
        result.end_to_end[suffix] = len(scans) / seconds
    tick("end to end")
    with tempfile.TemporaryDirectory() as folder:
        many, result.jobs_scans = _repeated_log(log, len(scans), Path(folder))
        chosen = slice(0, result.jobs_scans)
        result.other_cores_busy = cores_busy()  # the load average counts this process's work
        result.load_before = list(os.getloadavg())
        for jobs in range(1, max_jobs + 1):
            seconds = min(
                _run_seconds(many, chosen, extractor, ".jsonl", jobs) for _ in range(repeats)
            )
            result.jobs[jobs] = result.jobs_scans / seconds
        result.load_after = list(os.getloadavg())
    tick("jobs")
    passes = [(s[0], s[0] > 0, *_bearings(s)) for s in stacks]
    result.floor_us = best(lambda: [one_pass(*arguments) for arguments in passes])
    if with_cold_start:
        result.cold = cold_start(method)
        tick("cold start")
    return result


def _repeated_log(log: Path, scans: int, folder: Path) -> tuple[Path, int]:
    """``log`` with its records :data:`JOBS_COPIES` times over, written in ``folder`` (a
    CARMEN log; any other is used as it is), and how many of its scans to run: ``scans``
    (the scans of the other stages) times :data:`JOBS_COPIES`, at most all."""
    from scanlines.io import CarmenReader, open_log
    from scanlines.io.text import open_text

    with open_log(log) as reader:
        if not isinstance(reader, CarmenReader):
            return log, scans
    with open_text(log) as handle:
        text = handle.read()
    many = folder / log.name.removesuffix(".gz")
    many.write_text(text * JOBS_COPIES)
    with open_log(many) as reader:
        return many, min(sum(1 for _ in reader), scans * JOBS_COPIES)


def _seconds(work: Callable[[], Any]) -> float:
    start = time.perf_counter()
    work()
    return time.perf_counter() - start


def _read(log: Path, count: int) -> int:
    from scanlines.io import open_log

    with open_log(log) as reader:
        return sum(1 for _ in itertools.islice(reader, count))


def _stacks(scans: list) -> list[tuple]:
    """The chunks ``scanlines run`` would extract, as ``Extractor.batch`` arguments."""
    from scanlines.runs.runner import CHUNK_SCANS, chunk_scans

    stacks = []
    for chunk in chunk_scans(enumerate(scans), CHUNK_SCANS):
        first = chunk.scans[0]
        ranges = np.stack([s.ranges for s in chunk.scans])
        stacks.append(
            (ranges, first.angle_min, first.angle_increment, first.range_min, first.range_max)
        )
    return stacks


def _bearings(stack: tuple) -> tuple[np.ndarray, np.ndarray]:
    ranges, angle_min, step = stack[0], stack[1], stack[2]
    bearings = angle_min + step * np.arange(ranges.shape[1])
    return np.cos(bearings), np.sin(bearings)


def _encode_all(scans: list, tables: list, suffix: str) -> None:
    from scanlines.io import open_writer

    with tempfile.TemporaryDirectory() as folder:
        writer = open_writer(Path(folder) / f"out{suffix}")
        start = 0
        for table in tables:
            chunk = scans[start : start + len(table)]
            writer.encode_chunk(list(range(start, start + len(table))), chunk, table)
            start += len(table)
        writer.abort()


def _run_seconds(log: Path, scans: slice, extractor: Any, suffix: str, jobs: int) -> float:
    from scanlines.io import open_log
    from scanlines.runs.runner import run_log_to_file

    with tempfile.TemporaryDirectory() as folder, open_log(log) as reader:
        start = time.perf_counter()
        run_log_to_file(reader, extractor, Path(folder) / f"out{suffix}", scans=scans, jobs=jobs)
        return time.perf_counter() - start
