"""What ``scanlines bench`` measured: timings per method and dataset, and their tables.

:class:`BenchResult` holds everything one run measured (:func:`scanlines.bench.measure.run`)
and gives it as JSON (:meth:`BenchResult.to_dict`, schema :data:`SCHEMA`) and as tables
(:class:`~scanlines.report.TableData`) for the command and the performance page
(:mod:`tools.bench.performance_page`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.bench.config import BenchConfig
from scanlines.bench.timing import Timed
from scanlines.outputs import write_text_atomically
from scanlines.report import MISSING, TableData, microseconds, number

__all__ = [
    "SCHEMA",
    "BatchResult",
    "BatchRow",
    "BenchResult",
    "DatasetResult",
    "ScalingResult",
    "Timing",
]

SCHEMA = "scanlines-bench/1"
"""Value of ``"schema"`` in the JSON output."""


@dataclass
class Timing:
    """Per-scan timing of one method on one dataset (microseconds)."""

    status: str  # "ok" or "error"
    samples: int = 0
    median_us: float | None = None
    p90_us: float | None = None
    mean_us: float | None = None
    min_us: float | None = None
    scans_per_s: float | None = None
    ratio: float | None = None
    error: str | None = None

    @classmethod
    def from_timed(cls, timed: Timed[Any]) -> Timing:
        """The summary of :func:`~scanlines.bench.timing.time_calls` samples."""
        if timed.failure is not None or not timed.n_samples:
            error = timed.failure.describe() if timed.failure is not None else "no samples"
            return cls(status="error", samples=timed.n_samples, error=error)
        us = timed.samples_ns.ravel().astype(np.float64) / 1000.0
        mean = float(us.mean())
        return cls(
            status="ok",
            samples=int(us.size),
            median_us=float(np.median(us)),
            p90_us=float(np.percentile(us, 90)),
            mean_us=mean,
            min_us=float(us.min()),
            scans_per_s=1e6 / mean if mean > 0 else None,
        )

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclass
class DatasetResult:
    """All methods on one dataset."""

    name: str
    kind: str  # "real" or "simulated"
    description: str
    n_scans: int
    n_beams: list[int]
    timings: dict[str, Timing]

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "kind": self.kind,
            "description": self.description,
            "n_scans": self.n_scans,
            "n_beams": self.n_beams,
            "results": {m: t.to_dict() for m, t in self.timings.items()},
        }


@dataclass
class ScalingResult:
    """One scene at increasing beam counts over the same field of view."""

    description: str
    n_scans: int
    entries: list[tuple[int, dict[str, Timing]]]  # (beams, method -> timing)
    methods: tuple[str, ...]

    def exponents(self, method: str) -> tuple[float | None, float | None]:
        """Slope of log(us/scan) over log(beams): least squares on all counts, last two counts."""
        points = [
            (n, t[method].median_us)
            for n, t in self.entries
            if t[method].ok and t[method].median_us
        ]
        if len(points) < 2:
            return None, None
        x = np.log([p[0] for p in points])
        y = np.log([p[1] for p in points])
        fit = float(np.polyfit(x, y, 1)[0])
        top = float((y[-1] - y[-2]) / (x[-1] - x[-2]))
        return fit, top

    def to_dict(self) -> dict[str, Any]:
        entries = []
        for n, timings in self.entries:
            results = {}
            for m, t in timings.items():
                row = t.to_dict()
                row["us_per_beam"] = t.median_us / n if t.ok and t.median_us is not None else None
                results[m] = row
            entries.append({"n_beams": n, "results": results})
        exponents = {}
        for m in self.methods:
            fit, top = self.exponents(m)
            exponents[m] = {"fit": fit, "last_two": top}
        return {
            "description": self.description,
            "n_scans": self.n_scans,
            "entries": entries,
            "exponent": exponents,
        }


@dataclass
class BatchRow:
    """``Extractor.batch`` against the loop, one method on one real excerpt."""

    loop_us: float | None = None  # per scan, loop over the Scan objects of the log
    loop_rows_us: float | None = None  # per scan, loop building Scan(row, ...) as batch does
    batch_us: float | None = None  # per scan, one batch() call over the stack
    ratio: float | None = None  # batch_us / loop_us
    error: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclass
class BatchResult:
    dataset: str
    n_scans: int
    n_beams: int
    rows: dict[str, BatchRow]

    def to_dict(self) -> dict[str, Any]:
        return {
            "dataset": self.dataset,
            "n_scans": self.n_scans,
            "n_beams": self.n_beams,
            "results": {m: r.to_dict() for m, r in self.rows.items()},
        }


@dataclass
class BenchResult:
    """Everything one ``scanlines bench`` run measured."""

    config: BenchConfig
    command: str
    machine: dict[str, Any]
    reference: str
    reference_note: str
    datasets: list[DatasetResult]
    scaling: ScalingResult | None
    batch: list[BatchResult]
    profile: dict[str, Any] | None
    started: str
    elapsed_s: float
    load_after: list[float] | None = None
    pipeline: Any = None  # pipeline.PipelineResult

    @property
    def methods(self) -> tuple[str, ...]:
        return self.config.methods

    def to_dict(self) -> dict[str, Any]:
        return {
            "schema": SCHEMA,
            "command": self.command,
            "started": self.started,
            "elapsed_s": self.elapsed_s,
            "machine": {**self.machine, "loadavg_after": self.load_after},
            "settings": self.config.to_dict(),
            "methods": list(self.methods),
            "reference": {"method": self.reference, "note": self.reference_note},
            "datasets": [d.to_dict() for d in self.datasets],
            "scaling": self.scaling.to_dict() if self.scaling else None,
            "batch": [b.to_dict() for b in self.batch],
            "profile": self.profile,
            "pipeline": self.pipeline.to_dict() if self.pipeline else None,
        }

    def to_json(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` as JSON (atomically); returns the path."""
        text = json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"
        return write_text_atomically(Path(path), text, make_folder=True)

    # ----------------------------------------------------------------- tables

    def summary_table(self) -> TableData:
        columns = ["method", *[d.name for d in self.datasets], "geo. mean"]
        rows = []
        for m in self.methods:
            cells, logs = [], []
            for d in self.datasets:
                t = d.timings[m]
                if not t.ok:
                    cells.append("error")
                elif t.ratio is None:
                    cells.append(MISSING)
                else:
                    cells.append(number(t.ratio))
                    logs.append(math.log(t.ratio))
            geo = number(math.exp(sum(logs) / len(logs))) if logs else MISSING
            rows.append((m, *cells, geo))
        return TableData(
            title=f"Median time per scan relative to {self.reference} (below 1: faster)",
            columns=tuple(columns),
            rows=tuple(rows),
            caption=self.reference_note,
        )

    def dataset_tables(self) -> list[TableData]:
        tables = []
        repeats = self.config.repeats
        for d in self.datasets:
            rows, notes = [], []
            for m in self.methods:
                t = d.timings[m]
                if t.ok:
                    rows.append(
                        (
                            m,
                            microseconds(t.median_us),
                            microseconds(t.p90_us),
                            number(t.scans_per_s, ",.0f"),
                            number(t.ratio),
                        )
                    )
                else:
                    rows.append((m, "error", "", "", ""))
                    notes.append(f"{m}: {t.error}")
            beams = "/".join(str(n) for n in d.n_beams)
            title = (
                f"{d.name}: {d.n_scans} scans x {beams} beams, "
                f"{repeats} repeat{'s' if repeats != 1 else ''}"
            )
            caption = "; ".join([d.description, *(f"error: {n}" for n in notes)])
            tables.append(
                TableData(
                    title=title,
                    columns=(
                        "method",
                        "median us/scan",
                        "p90 us/scan",
                        "scans/s",
                        f"x {self.reference}",
                    ),
                    rows=tuple(rows),
                    caption=caption,
                )
            )
        return tables

    def scaling_tables(self) -> list[TableData]:
        s = self.scaling
        if s is None:
            return []
        counts = [n for n, _ in s.entries]
        per_scan, per_beam, notes = [], [], []
        for m in self.methods:
            a, b = [m], [m]
            for n, timings in s.entries:
                t = timings[m]
                if t.ok and t.median_us is not None:
                    a.append(microseconds(t.median_us))
                    b.append(microseconds(t.median_us / n))
                else:
                    a.append("error")
                    b.append("error")
                    notes.append(f"{m} at {n} beams: {t.error}")
            fit, top = s.exponents(m)
            a += [number(fit), number(top)]
            per_scan.append(tuple(a))
            per_beam.append(tuple(b))
        head = tuple(f"{n} beams" for n in counts)
        caption = (
            f"{s.description[0].upper()}{s.description[1:]}. "
            "k: exponent of us/scan ~ beams^k (k = 1: linear); fit: least squares over all "
            "counts (fixed per-call overhead pulls it below 1), last two: between the two "
            "largest counts."
        )
        if notes:
            caption += " Errors: " + "; ".join(notes)
        return [
            TableData(
                title="Scaling: median us/scan by beam count",
                columns=("method", *head, "k (fit)", "k (last two)"),
                rows=tuple(per_scan),
                caption=caption,
            ),
            TableData(
                title="Scaling: median us per beam (flat: linear)",
                columns=("method", *head),
                rows=tuple(per_beam),
            ),
        ]

    def batch_table(self) -> TableData | None:
        if not self.batch:
            return None
        rows, notes = [], []
        for b in self.batch:
            for m in self.methods:
                r = b.rows[m]
                if r.error is not None:
                    rows.append((b.dataset, m, "error", "", "", ""))
                    notes.append(f"{m} on {b.dataset}: {r.error}")
                    continue
                rows.append(
                    (
                        b.dataset,
                        m,
                        microseconds(r.loop_us),
                        microseconds(r.loop_rows_us),
                        microseconds(r.batch_us),
                        number(r.ratio),
                    )
                )
        sizes = ", ".join(f"{b.dataset} {b.n_scans} x {b.n_beams}" for b in self.batch)
        caption = (
            f"Stacks: {sizes} (scans x beams). "
            "us per scan, median over repeats of the whole pass. loop: extractor(scan) over "
            "the log's Scan objects; loop + Scan(): building Scan(row, ...) from the stacked "
            "ranges in the loop, as batch() does; batch: one Extractor.batch(stack, ...) call."
        )
        if notes:
            caption += " Errors: " + "; ".join(notes)
        return TableData(
            title="Extractor.batch vs the single-call loop, us/scan",
            columns=("dataset", "method", "loop", "loop + Scan()", "batch", "batch / loop"),
            rows=tuple(rows),
            caption=caption,
            left=2,
        )

    def profile_tables(self) -> list[TableData]:
        p = self.profile
        if p is None:
            return []
        cumulative = tuple(
            (
                f["function"],
                f["where"],
                f"{f['calls']:,}",
                f"{f['own_s']:.3f}",
                f"{f['cumulative_s']:.3f}",
                f"{f['cumulative_pct']:.1f}",
            )
            for f in p["cumulative"]
        )
        own = tuple(
            (
                f["function"],
                f["where"],
                f"{f['calls']:,}",
                f"{f['own_s']:.3f}",
                f"{f['own_pct']:.1f}",
            )
            for f in p["own"]
        )
        return [
            TableData(
                title=f"Top {len(cumulative)} functions within scanlines by cumulative time",
                columns=("function", "where", "calls", "own s", "cumulative s", "% of total"),
                rows=cumulative,
                left=2,
            ),
            TableData(
                title=f"Top {len(own)} functions by own time (all code, numpy included)",
                columns=("function", "where", "calls", "own s", "% of total"),
                rows=own,
                left=2,
            ),
        ]

    def tables(self) -> list[TableData]:
        """Summary, per dataset, scaling and batch tables (not the profile)."""
        out = [self.summary_table(), *self.dataset_tables(), *self.scaling_tables()]
        batch = self.batch_table()
        if batch is not None:
            out.append(batch)
        if self.pipeline is not None:
            out += self.pipeline.tables()
        return out
