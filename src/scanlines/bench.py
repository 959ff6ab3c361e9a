"""Speed of the registered methods, measured in one process: ``scanlines bench``.

What is timed
-------------
Every selected method on the same scans, in one process:

* the shipped real excerpts (:func:`scanlines.data.sample`: ``"intel"``, ``"freiburg"``),
  the first ``real_scans`` scans of each;
* simulated scans of each sensor preset (:data:`scanlines.sim.SENSORS`): scan ``i`` is
  ``random_scene(seed + i, sensor).scan(seed + i).scan``;
* a scaling run: one scene scanned over the same 180 deg field of view at increasing
  angular resolution (``beam_counts``, 100 to 10,000 beams by default), to show whether
  the cost is linear in the number of beams;
* :meth:`Extractor.batch <scanlines.Extractor.batch>` against the single-call loop on the
  real excerpts (scans of one sensor, equal beam count, stacked);
* optionally a :mod:`cProfile` run of the default extractor (``adaptive``) over the intel
  excerpt: the functions within scanlines by cumulative time.

How
---
One :class:`~scanlines.Extractor` per method (default parameters) for the whole run.
Per (method, dataset): ``warmup`` untimed calls on the first scans, then ``repeats`` passes
over the dataset's scans in a fixed order; every call is one sample, timed with
:func:`time.perf_counter_ns`. Passes are interleaved between methods (repeat 1 of every
method, then repeat 2, ...) so that a slow drift of the machine spreads over all methods.
Reported: median and 90th percentile of the samples in microseconds per scan, and scans per
second (``1e6 / mean``). The ratio of a method is its median over the reference method's
median on the same dataset in the same run (``iepf``, or the first selected method when iepf
is not selected). A method that raises on a scan is reported as an error for that dataset
(the scan and the message) and not timed further there; the bench goes on.

``import scanlines.bench`` needs only numpy; the command (``scanlines.cli.bench``) adds the
rich tables and the progress bar.
"""

from __future__ import annotations

import cProfile
import dataclasses
import datetime as _dt
import gc
import itertools
import json
import math
import os
import platform
import pstats
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ParameterError
from scanlines.extractor import Extractor
from scanlines.extractor import method_names as registered_methods
from scanlines.io.writers import write_text_atomically
from scanlines.scan import Scan

__all__ = [
    "DEFAULT_BEAMS",
    "QUICK_BEAMS",
    "REFERENCE",
    "SCHEMA",
    "BenchConfig",
    "BenchResult",
    "TableData",
    "machine_info",
    "profile_extractor",
    "render_markdown",
    "run",
    "write_docs",
]

SCHEMA = "scanlines-bench/1"
"""Value of ``"schema"`` in the JSON output."""

REFERENCE = "iepf"
"""The method the ratios refer to when it is selected."""

SAMPLE_NAMES = ("intel", "freiburg")
DEFAULT_BEAMS = (100, 300, 1000, 3000, 10000)
QUICK_BEAMS = (100, 1000)
MAX_BEAMS = 100_000

Progress = Callable[[str, int, int], None]
"""``progress(stage, done, total)``: called after every unit of work."""


# --------------------------------------------------------------------------- configuration


@dataclass(frozen=True)
class BenchConfig:
    """What to time and how often.

    Parameters
    ----------
    methods:
        Method names; empty: every registered method, in registry order.
    sensors:
        Sensor presets for the simulated datasets; empty: all presets.
    real_scans:
        Scans taken from the start of each real excerpt.
    sim_scans:
        Simulated scans (one scene each) per sensor preset.
    repeats:
        Timed passes over each dataset.
    warmup:
        Untimed calls per (method, dataset) before timing.
    beam_counts:
        Beam counts of the scaling run (empty: no scaling run).
    scaling_scans:
        Scans (noise draws of the one scene) per beam count.
    seed:
        Base seed of the simulated scenes and noise.
    batch:
        Time :meth:`Extractor.batch` against the loop on the real excerpts.
    profile:
        Run :mod:`cProfile` on the default extractor over the intel excerpt.
    profile_scans:
        Intel scans profiled; ``None``: the whole excerpt.
    profile_top:
        Functions listed by the profile.
    quick:
        Recorded in the output (set by :meth:`quick`).
    """

    methods: tuple[str, ...] = ()
    sensors: tuple[str, ...] = ()
    real_scans: int = 100
    sim_scans: int = 50
    repeats: int = 3
    warmup: int = 3
    beam_counts: tuple[int, ...] = DEFAULT_BEAMS
    scaling_scans: int = 10
    seed: int = 0
    batch: bool = True
    profile: bool = False
    profile_scans: int | None = None
    profile_top: int = 15
    quick: bool = False

    @classmethod
    def quick_config(cls, **changes: Any) -> BenchConfig:
        """A tiny run for CI: few scans, one repeat, beam counts 100 and 1000."""
        base = cls(
            real_scans=5,
            sim_scans=3,
            repeats=1,
            warmup=1,
            beam_counts=QUICK_BEAMS,
            scaling_scans=2,
            profile_scans=5,
            quick=True,
        )
        return dataclasses.replace(base, **changes)

    def validated(self) -> BenchConfig:
        """This configuration with methods and sensors resolved and checked.

        Raises
        ------
        ParameterError
            For an unknown method or sensor preset, or a count out of range.
        """
        from scanlines.sim import SENSORS, get_sensor

        chosen = tuple(dict.fromkeys(self.methods)) or registered_methods()
        for name in chosen:
            Extractor(name)  # raises ParameterError naming the valid methods
        sensors = tuple(dict.fromkeys(self.sensors)) or tuple(SENSORS)
        for name in sensors:
            get_sensor(name)
        for label, value, low in (
            ("real scans", self.real_scans, 1),
            ("simulated scans", self.sim_scans, 1),
            ("repeats", self.repeats, 1),
            ("warm-up calls", self.warmup, 0),
            ("scaling scans", self.scaling_scans, 1),
            ("profile functions", self.profile_top, 1),
        ):
            if value < low:
                raise ParameterError(f"{label} must be >= {low}, got {value}")
        if self.profile_scans is not None and self.profile_scans < 1:
            raise ParameterError(f"profile scans must be >= 1, got {self.profile_scans}")
        beams = tuple(sorted(set(self.beam_counts)))
        for n in beams:
            if not 2 <= n <= MAX_BEAMS:
                raise ParameterError(f"beam counts must be in 2..{MAX_BEAMS}, got {n}")
        return dataclasses.replace(self, methods=chosen, sensors=sensors, beam_counts=beams)

    def to_dict(self) -> dict[str, Any]:
        return {
            "methods": list(self.methods),
            "sensors": list(self.sensors),
            "real_scans": self.real_scans,
            "sim_scans": self.sim_scans,
            "repeats": self.repeats,
            "warmup": self.warmup,
            "beam_counts": list(self.beam_counts),
            "scaling_scans": self.scaling_scans,
            "seed": self.seed,
            "batch": self.batch,
            "profile": self.profile,
            "profile_scans": self.profile_scans,
            "quick": self.quick,
        }


# --------------------------------------------------------------------------- results


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
    def from_samples(cls, samples_ns: Sequence[int], error: str | None) -> Timing:
        if error is not None or not samples_ns:
            return cls(status="error", samples=len(samples_ns), error=error or "no samples")
        us = np.asarray(samples_ns, dtype=np.float64) / 1000.0
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


@dataclass(frozen=True)
class TableData:
    """A table as text cells, rendered by the command (rich) and the docs (markdown)."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    caption: str = ""
    left: int = 1  # leading columns aligned left; the rest are numbers, aligned right


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
        }

    def to_json(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` as JSON (atomically); returns the path."""
        text = json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"
        return write_text_atomically(Path(path), text)

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
                    cells.append("-")
                else:
                    cells.append(_fmt_ratio(t.ratio))
                    logs.append(math.log(t.ratio))
            geo = _fmt_ratio(math.exp(sum(logs) / len(logs))) if logs else "-"
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
                            _fmt_us(t.median_us),
                            _fmt_us(t.p90_us),
                            _fmt_rate(t.scans_per_s),
                            _fmt_ratio(t.ratio) if t.ratio is not None else "-",
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
                    a.append(_fmt_us(t.median_us))
                    b.append(_fmt_us(t.median_us / n))
                else:
                    a.append("error")
                    b.append("error")
                    notes.append(f"{m} at {n} beams: {t.error}")
            fit, top = s.exponents(m)
            a += [_fmt_exp(fit), _fmt_exp(top)]
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
                        _fmt_us(r.loop_us),
                        _fmt_us(r.loop_rows_us),
                        _fmt_us(r.batch_us),
                        _fmt_ratio(r.ratio) if r.ratio is not None else "-",
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
        return out


# --------------------------------------------------------------------------- formatting


def _fmt_us(value: float | None) -> str:
    if value is None:
        return "-"
    if value >= 100:
        return f"{value:,.0f}"
    if value >= 10:
        return f"{value:.1f}"
    if value >= 1:
        return f"{value:.2f}"
    return f"{value:.3f}"


def _fmt_rate(value: float | None) -> str:
    return "-" if value is None else f"{value:,.0f}"


def _fmt_ratio(value: float) -> str:
    return f"{value:.2f}"


def _fmt_exp(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


# --------------------------------------------------------------------------- machine


def machine_info() -> dict[str, Any]:
    """CPU, cores, Python, numpy and BLAS, thread-count environment variables, load."""
    cpu, physical = _cpu_from_proc()
    try:
        usable = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        usable = None
    thread_vars = sorted(
        k
        for k in os.environ
        if k.startswith("OPENBLAS") or k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS")
    )
    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        load = None
    return {
        "cpu": cpu or platform.processor() or "unknown",
        "cores_logical": os.cpu_count(),
        "cores_physical": physical,
        "cores_usable": usable,
        "platform": platform.platform(),
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "numpy": np.__version__,
        "numba": _numba_version(),
        "blas": _blas(),
        "openblas_env": {k: os.environ[k] for k in thread_vars if k.startswith("OPENBLAS")},
        "thread_env": {k: os.environ[k] for k in thread_vars if not k.startswith("OPENBLAS")},
        "loadavg_before": load,
    }


def _cpu_from_proc() -> tuple[str | None, int | None]:
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None, None
    model = None
    cores: set[tuple[str, str]] = set()
    physical_id = core_id = None
    for line in text.splitlines():
        key, _, value = line.partition(":")
        key, value = key.strip(), value.strip()
        if key == "model name" and model is None:
            model = value
        elif key == "physical id":
            physical_id = value
        elif key == "core id":
            core_id = value
        elif not key and physical_id is not None and core_id is not None:
            cores.add((physical_id, core_id))
            physical_id = core_id = None
    if physical_id is not None and core_id is not None:
        cores.add((physical_id, core_id))
    return model, (len(cores) or None)


def _numba_version() -> str | None:
    from scanlines._jit import COMPILED

    if not COMPILED:
        return None
    import numba

    return numba.__version__


def _blas() -> str | None:
    try:
        config = np.show_config(mode="dicts")
        blas = config["Build Dependencies"]["blas"]
        return f"{blas.get('name', '?')} {blas.get('version', '')}".strip()
    except Exception:  # older numpy, or a layout change: not worth failing the bench
        return None


# --------------------------------------------------------------------------- datasets


@dataclass
class _Dataset:
    name: str
    kind: str
    description: str
    scans: list[Scan] = field(default_factory=list)

    @property
    def beam_counts(self) -> list[int]:
        return sorted({len(s) for s in self.scans})


def _real_dataset(name: str, n: int | None) -> _Dataset:
    from scanlines.data import sample
    from scanlines.io import open_log

    scans = list(itertools.islice(open_log(sample(name)), n))
    if not scans:
        raise ParameterError(f"the {name} excerpt holds no scans")
    descriptions = {
        "intel": "Intel Research Lab, SICK LMS (real)",
        "freiburg": "Freiburg building 079, SICK LMS (real)",
    }
    return _Dataset(name, "real", descriptions.get(name, f"{name} (real)"), scans)


def _sim_dataset(sensor: str, n: int, seed: int) -> _Dataset:
    from scanlines.sim import get_sensor, random_scene

    spec = get_sensor(sensor)
    scans = [random_scene(seed + i, spec).scan(seed + i).scan for i in range(n)]
    return _Dataset(
        f"sim:{sensor}", "simulated", f"{spec.description} (simulated, one scene per scan)", scans
    )


def _scaling_sensor(n_beams: int):
    from scanlines.sim import get_sensor

    return dataclasses.replace(
        get_sensor("lms_1deg"),
        n_beams=n_beams,
        angle_increment=math.pi / (n_beams - 1),
        angle_min=-math.pi / 2,
    )


# --------------------------------------------------------------------------- timing


def _describe(index: int, error: BaseException) -> str:
    message = str(error).splitlines()[0] if str(error) else ""
    return f"scan {index}: {type(error).__name__}: {message}"[:300]


def _measure(
    extractors: dict[str, Extractor],
    scans: Sequence[Scan],
    repeats: int,
    warmup: int,
    tick: Callable[[], None],
) -> dict[str, Timing]:
    """Per-scan samples of every extractor over ``scans``; passes interleaved between methods."""
    samples: dict[str, list[int]] = {m: [] for m in extractors}
    errors: dict[str, str] = {}
    for m, ex in extractors.items():
        for i, scan in enumerate(scans[:warmup]):
            try:
                ex(scan)
            except Exception as error:
                errors[m] = _describe(i, error)
                break
    gc.collect()
    clock = time.perf_counter_ns
    for _ in range(repeats):
        for m, ex in extractors.items():
            if m not in errors:
                out = samples[m]
                i = 0
                try:
                    for i, scan in enumerate(scans):  # noqa: B007 (i names the failing scan)
                        start = clock()
                        ex(scan)
                        out.append(clock() - start)
                except Exception as error:
                    errors[m] = _describe(i, error)
            tick()
    return {m: Timing.from_samples(samples[m], errors.get(m)) for m in extractors}


def _set_ratios(timings: dict[str, Timing], reference: str) -> None:
    ref = timings.get(reference)
    for m, t in timings.items():
        if not t.ok or ref is None or not ref.ok or not ref.median_us:
            t.ratio = None
        elif m == reference:
            t.ratio = 1.0
        else:
            t.ratio = t.median_us / ref.median_us


def _stack_group(scans: Sequence[Scan]) -> list[Scan]:
    """The largest group of scans sharing beam count, angles and range limits."""
    groups: dict[tuple, list[Scan]] = {}
    for s in scans:
        key = (len(s), s.angle_min, s.angle_increment, s.range_min, s.range_max)
        groups.setdefault(key, []).append(s)
    return max(groups.values(), key=len)


def _measure_batch(
    extractors: dict[str, Extractor],
    scans: Sequence[Scan],
    repeats: int,
    warmup: int,
    tick: Callable[[], None],
) -> tuple[int, int, dict[str, BatchRow]]:
    group = _stack_group(scans)
    first = group[0]
    stack = np.stack([s.ranges for s in group])
    geometry = (first.angle_min, first.angle_increment, first.range_min, first.range_max)
    n = len(group)

    def loop(ex: Extractor) -> None:
        for s in group:
            ex(s)

    def loop_rows(ex: Extractor) -> None:
        for row in stack:
            ex(Scan(row, *geometry))

    def batch(ex: Extractor) -> None:
        ex.batch(stack, *geometry)

    variants = {"loop": loop, "loop_rows": loop_rows, "batch": batch}
    totals: dict[str, dict[str, list[int]]] = {m: {k: [] for k in variants} for m in extractors}
    errors: dict[str, str] = {}
    for m, ex in extractors.items():
        try:
            ex.batch(stack[: max(warmup, 1)], *geometry)
        except Exception as error:
            errors[m] = f"warm-up batch: {type(error).__name__}: {error}"[:300]
    gc.collect()
    clock = time.perf_counter_ns
    names = list(variants)
    for r in range(repeats):
        order = names[r % 3 :] + names[: r % 3]  # rotate so no variant always runs first
        for m, ex in extractors.items():
            if m not in errors:
                for k in order:
                    try:
                        start = clock()
                        variants[k](ex)
                        totals[m][k].append(clock() - start)
                    except Exception as error:
                        errors[m] = f"{k}: {type(error).__name__}: {error}"[:300]
                        break
            tick()
    rows = {}
    for m in extractors:
        if m in errors:
            rows[m] = BatchRow(error=errors[m])
            continue
        per = {k: float(np.median(v)) / 1000.0 / n for k, v in totals[m].items()}
        rows[m] = BatchRow(
            loop_us=per["loop"],
            loop_rows_us=per["loop_rows"],
            batch_us=per["batch"],
            ratio=per["batch"] / per["loop"] if per["loop"] > 0 else None,
        )
    return n, len(first), rows


# --------------------------------------------------------------------------- profile


def profile_extractor(scans: Sequence[Scan], top: int = 15, method: str = "adaptive") -> dict:
    """:mod:`cProfile` of ``Extractor(method)`` over ``scans``.

    Returns the profiled time and two lists: the ``top`` functions within scanlines by
    cumulative time, and the ``top`` functions of any code by own time.
    """
    import scanlines

    extractor = Extractor(method)
    extractor(scans[0])  # warm the bearing tables, as a long-running user would have them
    profiler = cProfile.Profile()
    profiler.enable()
    for scan in scans:
        extractor(scan)
    profiler.disable()
    stats = pstats.Stats(profiler)
    # Percentages are of the profiled total; the outermost cumulative time can exceed the
    # sum of own times by the profiler's bookkeeping, so take the larger of the two.
    total = max(
        float(stats.total_tt),  # type: ignore[attr-defined]
        max((v[3] for v in stats.stats.values()), default=0.0),  # type: ignore[attr-defined]
        1e-12,
    )
    package = Path(scanlines.__file__).resolve().parent
    root = package.parent

    def where(filename: str, line: int) -> tuple[str, bool]:
        path = Path(filename)
        try:
            inside = path.resolve().is_relative_to(package)
        except (OSError, ValueError):
            inside = False
        if inside:
            return f"{path.resolve().relative_to(root)}:{line}", True
        if filename == "~":
            return "(built-in)", False
        parts = path.parts
        if "site-packages" in parts:
            parts = parts[parts.index("site-packages") + 1 :]
        return f"{'/'.join(parts[-3:])}:{line}", False

    rows = []
    for (filename, line, func), (_cc, ncalls, own, cumulative, _callers) in stats.stats.items():  # type: ignore[attr-defined]
        place, inside = where(filename, line)
        rows.append(
            {
                "function": func,
                "where": place,
                "inside": inside,
                "calls": int(ncalls),
                "own_s": float(own),
                "cumulative_s": float(cumulative),
                "own_pct": 100.0 * own / total,
                "cumulative_pct": 100.0 * cumulative / total,
            }
        )
    cumulative = sorted((r for r in rows if r["inside"]), key=lambda r: -r["cumulative_s"])
    own = sorted(rows, key=lambda r: -r["own_s"])
    for r in rows:
        del r["inside"]
    return {
        "method": method,
        "dataset": "intel",
        "n_scans": len(scans),
        "profiled_s": total,
        "us_per_scan_profiled": 1e6 * total / len(scans),
        "cumulative": cumulative[:top],
        "own": own[:top],
    }


# --------------------------------------------------------------------------- run


def run(
    config: BenchConfig | None = None,
    *,
    command: str = "",
    progress: Progress | None = None,
) -> BenchResult:
    """Time the methods as ``config`` says; see the module docstring.

    Raises
    ------
    ParameterError
        For a bad configuration (checked before anything is timed).
    """
    config = (config or BenchConfig()).validated()
    started = _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat()
    machine = machine_info()
    t0 = time.perf_counter()
    methods = config.methods
    if REFERENCE in methods:
        reference, note = REFERENCE, f"Ratios are to {REFERENCE}, measured in the same run."
    else:
        reference = methods[0]
        why = "not registered" if REFERENCE not in registered_methods() else "not selected"
        note = (
            f"{REFERENCE} is {why}: ratios are to {reference}, the first selected method, "
            "measured in the same run."
        )
    extractors = {m: Extractor(m) for m in methods}
    n_methods = len(methods)
    real_names = SAMPLE_NAMES
    n_sets = len(real_names) + len(config.sensors)
    total = (
        n_sets  # loading / simulating
        + n_sets * config.repeats * n_methods
        + len(config.beam_counts) * (1 + config.repeats * n_methods)
        + (len(real_names) * config.repeats * n_methods if config.batch else 0)
        + (1 if config.profile else 0)
    )
    done = 0

    def tick(stage: str) -> Callable[[], None]:
        def advance() -> None:
            nonlocal done
            done += 1
            if progress is not None:
                progress(stage, done, total)

        return advance

    # datasets
    sets: list[_Dataset] = []
    for name in real_names:
        sets.append(_real_dataset(name, config.real_scans))
        tick(f"reading {name}")()
    for sensor in config.sensors:
        sets.append(_sim_dataset(sensor, config.sim_scans, config.seed))
        tick(f"simulating {sensor}")()

    results = []
    for d in sets:
        timings = _measure(extractors, d.scans, config.repeats, config.warmup, tick(d.name))
        _set_ratios(timings, reference)
        results.append(
            DatasetResult(d.name, d.kind, d.description, len(d.scans), d.beam_counts, timings)
        )

    # scaling
    scaling = None
    if config.beam_counts:
        from scanlines.sim import random_scene

        layout = _scaling_sensor(181)
        scene = random_scene(config.seed, layout)
        entries = []
        for n in config.beam_counts:
            spec = _scaling_sensor(n)
            scans = [
                scene.scan(config.seed + i, sensor=spec).scan for i in range(config.scaling_scans)
            ]
            tick(f"scaling: simulating {n} beams")()
            timings = _measure(
                extractors, scans, config.repeats, config.warmup, tick(f"scaling: {n} beams")
            )
            _set_ratios(timings, reference)
            entries.append((n, timings))
        description = (
            f"one {scene.kind} scene (seed {config.seed}) scanned by the lms_1deg preset "
            f"widened to -90..+90 deg at pi/(beams-1) steps; {config.scaling_scans} noise "
            f"draws per count x {config.repeats} repeat{'s' if config.repeats != 1 else ''}"
        )
        scaling = ScalingResult(description, config.scaling_scans, entries, methods)

    # batch vs loop
    batch = []
    if config.batch:
        for d in sets[: len(real_names)]:
            n, beams, rows = _measure_batch(
                extractors, d.scans, config.repeats, config.warmup, tick(f"batch: {d.name}")
            )
            batch.append(BatchResult(d.name, n, beams, rows))

    # profile
    profile = None
    if config.profile:
        scans = _real_dataset("intel", config.profile_scans).scans
        profile = profile_extractor(scans, config.profile_top)
        tick("profiling adaptive")()

    try:
        load_after = [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        load_after = None
    return BenchResult(
        config=config,
        command=command,
        machine=machine,
        reference=reference,
        reference_note=note,
        datasets=results,
        scaling=scaling,
        batch=batch,
        profile=profile,
        started=started,
        elapsed_s=round(time.perf_counter() - t0, 1),
        load_after=load_after,
    )


# --------------------------------------------------------------------------- markdown


def _md_table(table: TableData, heading: str = "###") -> str:
    def cell(text: str) -> str:
        return text.replace("|", "\\|")

    lines = [f"{heading} {table.title}", ""]
    lines.append("| " + " | ".join(cell(c) for c in table.columns) + " |")
    lines.append(
        "|"
        + "|".join(":---" if i < table.left else "---:" for i in range(len(table.columns)))
        + "|"
    )
    for row in table.rows:
        lines.append("| " + " | ".join(cell(c) for c in row) + " |")
    if table.caption:
        lines += ["", table.caption]
    return "\n".join(lines) + "\n"


def _machine_lines(result: BenchResult) -> list[str]:
    m = result.machine
    cores = f"{m['cores_logical']} logical"
    if m.get("cores_physical"):
        cores += f", {m['cores_physical']} physical"
    if m.get("cores_usable") is not None:
        cores += f", {m['cores_usable']} usable by this process"
    openblas = (
        ", ".join(f"`{k}={v}`" for k, v in m["openblas_env"].items())
        if m["openblas_env"]
        else "none set"
    )
    threads = (
        ", ".join(f"`{k}={v}`" for k, v in m["thread_env"].items())
        if m["thread_env"]
        else "none set"
    )
    load_before = m.get("loadavg_before")
    load = (
        f"{' / '.join(f'{x:.2f}' for x in load_before)} before, "
        f"{' / '.join(f'{x:.2f}' for x in result.load_after)} after (1/5/15 min)"
        if load_before and result.load_after
        else "unknown"
    )
    return [
        f"- CPU: {m['cpu']} (`model name` in /proc/cpuinfo)",
        f"- Cores: {cores}",
        f"- OS: {m['platform']}",
        f"- Python: {m['python']}",
        f"- numpy: {m['numpy']}" + (f", BLAS: {m['blas']}" if m.get("blas") else ""),
        f"- numba: {m.get('numba') or 'not installed (kernels run as plain Python)'}; "
        "adaptive, iepf, pdbs and split_merge run as compiled kernels, line_tracking, "
        "line_regression, ransac and hough as numpy",
        f"- OPENBLAS environment variables: {openblas}",
        f"- Other thread-count variables (OMP_NUM_THREADS, MKL_NUM_THREADS): {threads}",
        f"- Load average: {load}",
        f"- Command: `{result.command}`",
        f"- Started {result.started} (UTC), took {result.elapsed_s:.0f} s",
    ]


def render_markdown(result: BenchResult) -> str:
    """``docs/PERFORMANCE.md``: machine, method, tables and profile of ``result``."""
    c = result.config
    command = result.command or "scanlines bench --write-docs"
    parts = [
        "# Performance\n",
        f"<!-- Generated by `{command}`. Do not edit: rerun the command. -->\n",
        f"> **Generated** by `{command}` (`scanlines.bench`) on {result.started[:10]}; do not "
        "edit by hand, rerun the command to update. Every number below is what that run "
        "measured on the machine described here.\n",
        "## Machine\n",
        "\n".join(_machine_lines(result)) + "\n",
        "## How it was measured\n",
        "\n".join(
            [
                f"- Methods: {', '.join(result.methods)}; one `Extractor(method)` each, "
                "default parameters, all in one process.",
                f"- Datasets: the first {c.real_scans} scans of the shipped real excerpts "
                f"(intel, freiburg) and {c.sim_scans} simulated scans per sensor preset "
                f"({', '.join(c.sensors)}; scan i: `random_scene({c.seed} + i, sensor)`, "
                "realistic noise). Every method gets the same scans in the same order.",
                f"- Per (method, dataset): {c.warmup} warm-up call{'s' if c.warmup != 1 else ''}, "
                f"then {c.repeats} timed pass{'es' if c.repeats != 1 else ''} over the scans, "
                "passes interleaved between methods; one `time.perf_counter_ns` sample per "
                "call. Median and p90 over the samples; scans/s = 1e6 / mean us.",
                f"- {result.reference_note}",
                "- A method that raises on a scan is an error for that dataset (shown, not timed).",
            ]
        )
        + "\n",
        "## Summary\n",
        _md_table(result.summary_table()),
        "## Per dataset\n",
        *[_md_table(t) for t in result.dataset_tables()],
    ]
    scaling = result.scaling_tables()
    if scaling:
        parts += ["## Scaling with the number of beams\n", *[_md_table(t) for t in scaling]]
    batch = result.batch_table()
    if batch is not None:
        parts += ["## Extractor.batch vs the loop\n", _md_table(batch)]
    if result.profile is not None:
        p = result.profile
        share = [
            f"`{f['function']}` ({f['where']}) {f['own_pct']:.0f}%"
            for f in p["cumulative"]
            if f["own_pct"] >= 5.0
        ]
        parts += [
            "## Where the time goes\n",
            f"`cProfile` of `Extractor()` ({p['method']}, default parameters) over "
            f"{p['n_scans']} scans of the {p['dataset']} excerpt: {p['profiled_s']:.2f} s "
            f"profiled, {p['us_per_scan_profiled']:,.0f} us/scan with the profiler's overhead "
            "(which inflates many small calls more than few large ones). Percentages are of "
            "the profiled total.\n",
            *[_md_table(t) for t in result.profile_tables()],
        ]
        if share:
            parts.append(
                "Functions within scanlines with at least 5% own time: " + ", ".join(share) + ".\n"
            )
    return "\n".join(parts)


def write_docs(result: BenchResult, path: str | Path) -> Path:
    """Write :func:`render_markdown` to ``path`` (atomically); returns the path."""
    return write_text_atomically(Path(path), render_markdown(result))


def command_line(argv: Sequence[str] | None = None) -> str:
    """``scanlines`` plus the arguments of this process, shell-quoted."""
    import shlex

    args = list(sys.argv[1:] if argv is None else argv)
    return shlex.join(["scanlines", *args])
