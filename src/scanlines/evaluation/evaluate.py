"""Score method specs on simulated scans with exact ground truth: :func:`evaluate`.

Run one or more method specs (:mod:`scanlines.evaluation.specs`) on the same generated
scenes of every sensor preset (:mod:`scanlines.evaluation.scenes`), score each
extraction with :func:`scanlines.evaluation.metrics.score` and pool the scores per
sensor and spec::

    from scanlines.evaluation.evaluate import evaluate

    result = evaluate(["adaptive", "adaptive:paper"], sensors=["tim571"], n=20)
    result.to_csv("out/")              # per_scan.csv, summary.csv
    result.to_json("out/summary.json")

The spec ``truth`` adds the truth row (:mod:`scanlines.evaluation.truth_row`), scored
like every method. :func:`worst_scans` ranks the scans by event F1; the figures are in
:mod:`scanlines.viz.evaluation`.

Timing
------
``us`` is the time of the extraction call alone, taken by
:mod:`scanlines.evaluation.timing` (one pass per scene: every spec on the scene's scan,
an untimed call, then the timed one), in microseconds; summaries report its median (and
mean) per sensor and spec. With ``workers > 1`` the processes share the machine, so
times are less comparable; compare speeds with ``scanlines bench``. For the truth row it
is the time of building the row from the truth.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import lru_cache, partial
from pathlib import Path
from typing import Any

import numpy as np

from scanlines import Extraction, ParameterError
from scanlines.evaluation.metrics import aggregate, score
from scanlines.evaluation.report import number, write_csv
from scanlines.evaluation.scenes import (
    DEFAULT_SCENES,
    OnScene,
    SceneCase,
    SceneSet,
    check_sensors,
    make_scene,
    scene_recipe,
)
from scanlines.evaluation.scores import ScanScore, Summary, Tolerances
from scanlines.evaluation.specs import MethodSpec, parse_specs
from scanlines.evaluation.timing import time_calls
from scanlines.evaluation.truth_row import truth_extraction
from scanlines.json_values import jsonable
from scanlines.sim import get_sensor

__all__ = [
    "ALL_SENSORS",
    "TABLE_COLUMNS",
    "WORST_BY",
    "EvalConfig",
    "EvalResult",
    "ScanRecord",
    "SummaryRecord",
    "WorstScan",
    "evaluate",
    "event_f1",
    "extract_case",
    "tolerance_caption",
    "tolerances_dict",
    "worst_scans",
]

ALL_SENSORS = "all"
"""The ``sensor`` of summary rows pooled over every sensor."""

WORST_BY = (
    "event F1: 2 TP / (2 TP + FP + FN) with breakpoints and corners pooled "
    "(1 when the scan has nothing counted), mean over the specs; lowest first"
)
"""How :func:`worst_scans` ranks scans."""


# --------------------------------------------------------------------------- running


def evaluate(
    specs: Iterable[str | MethodSpec],
    sensors: Sequence[str] | None = None,
    n: int | None = None,
    seed: int = 0,
    *,
    tol: Tolerances | None = None,
    noise: str = "realistic",
    scenes: SceneSet | None = None,
    workers: int = 1,
    on_scene: OnScene | None = None,
    clutter: bool = False,
) -> EvalResult:
    """Run every spec on the same scans and score them against the truth.

    Parameters
    ----------
    specs:
        Method specs (strings as in :func:`~scanlines.evaluation.specs.parse_spec`, or
        :class:`~scanlines.evaluation.specs.MethodSpec`).
    sensors:
        Sensor names (presets, or family names such as ``"family-03"``, see
        :mod:`scanlines.sim.family`); all of :data:`~scanlines.sim.SENSORS` when
        ``None``. With ``scenes``, a selection of the set's sensors.
    n:
        Scenes per sensor; 100 when ``None``. With ``scenes``, at most this many of
        each sensor (all when ``None``).
    seed:
        Base seed (see :func:`~scanlines.evaluation.scenes.scene_seed`); ignored with
        ``scenes``.
    tol:
        Tolerances; :class:`~scanlines.evaluation.scores.Tolerances` defaults when ``None``.
    noise:
        ``"realistic"`` or ``"exact"``; ignored with ``scenes``.
    scenes:
        Evaluate on this set instead of generating scenes.
    workers:
        Processes; each scene is generated once and all specs run on it.
    on_scene:
        Called as ``on_scene(done, total)`` after each scene.
    clutter:
        Generate clutter scenes (:data:`scanlines.sim.CLUTTER_KINDS`); ignored with
        ``scenes``.

    Returns
    -------
    EvalResult

    Raises
    ------
    ParameterError
        For a bad spec, an unknown sensor, ``n < 1``, a negative seed, an unknown
        noise or ``workers < 1``.
    """
    parsed = parse_specs(specs)
    tol = Tolerances() if tol is None else tol
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers must be an integer >= 1, got {workers!r}")
    if scenes is not None:
        scenes = scenes.select(sensors, n)
        jobs: list[Any] = list(scenes.cases)
        counts = scenes.per_sensor()
        config = EvalConfig(
            parsed,
            scenes.sensors,
            max(counts.values(), default=0),
            scenes.seed,
            scenes.noise,
            tol,
            scenes.source,
            scenes.clutter,
        )
    else:
        chosen = check_sensors(sensors)
        n = DEFAULT_SCENES if n is None else n
        recipe = scene_recipe(chosen, n, seed, noise)
        jobs = [(s, i, seed, noise, bool(clutter)) for s, i in recipe]
        config = EvalConfig(parsed, chosen, n, seed, noise, tol, clutter=bool(clutter))
    records = [r for batch in _run_jobs(jobs, parsed, tol, workers, on_scene) for r in batch]
    return EvalResult(config, tuple(records), _summarise(records, config), scenes)


def _run_jobs(
    jobs: list[Any],
    specs: tuple[MethodSpec, ...],
    tol: Tolerances,
    workers: int,
    on_scene: OnScene | None,
) -> Iterator[list[ScanRecord]]:
    work = partial(_run_job, specs=specs, tol=tol)
    if workers == 1 or len(jobs) < 2:
        results: Iterable[list[ScanRecord]] = map(work, jobs)
        yield from _counted(results, len(jobs), on_scene)
        return
    from concurrent.futures import ProcessPoolExecutor

    chunk = max(1, len(jobs) // (8 * workers))
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield from _counted(pool.map(work, jobs, chunksize=chunk), len(jobs), on_scene)


def _counted(
    results: Iterable[list[ScanRecord]], total: int, on_scene: OnScene | None
) -> Iterator[list[ScanRecord]]:
    for done, batch in enumerate(results, 1):
        if on_scene is not None:
            on_scene(done, total)
        yield batch


Runner = Callable[[SceneCase], Extraction]


@lru_cache(maxsize=32)
def _runner(spec: MethodSpec) -> Runner:
    """What ``spec`` does with a scene (one extractor per spec and process)."""
    if spec.is_truth:
        return _truth_row
    extractor = spec.extractor()
    return lambda case: extractor(case.scan)


def _truth_row(case: SceneCase) -> Extraction:
    """:func:`truth_extraction` of a scene, covariances from its preset's range noise."""
    sigma = get_sensor(case.sensor).noise.sigma if case.noise == "realistic" else 0.0
    return truth_extraction(case.scan, case.truth, range_sigma=sigma)


def extract_case(spec: MethodSpec, case: SceneCase) -> Extraction:
    """What ``spec`` finds in a scene: its extractor on the scan, or the truth row."""
    return _runner(spec)(case)


def _run_job(
    job: SceneCase | tuple[str, int, int, str, bool],
    *,
    specs: tuple[MethodSpec, ...],
    tol: Tolerances,
) -> list[ScanRecord]:
    """Score every spec on one scene (generated here from its recipe, or given).

    Every spec is timed on the scene's scan by :func:`~scanlines.evaluation.timing.time_calls`
    (one pass: an untimed extraction, then the timed one).
    """
    case = job if isinstance(job, SceneCase) else make_scene(*job)
    timed = time_calls({s.label: _runner(s) for s in specs}, [case])
    out = []
    for spec in specs:
        extraction = timed[spec.label].results[0]
        us = int(timed[spec.label].samples_ns[0, 0]) / 1000.0
        nonfinite = int(np.count_nonzero(~np.isfinite(extraction.lines).all(axis=1)))
        found = score(extraction, case.truth, case.scan, tol)
        out.append(
            ScanRecord(case.sensor, case.index, case.seed, case.kind, spec, us, nonfinite, found)
        )
    return out


def _summarise(records: list[ScanRecord], config: EvalConfig) -> tuple[SummaryRecord, ...]:
    groups = [*config.sensors, ALL_SENSORS] if len(config.sensors) > 1 else [*config.sensors]
    out = []
    for sensor in groups:
        for spec in config.specs:
            chosen = [
                r
                for r in records
                if r.spec.label == spec.label and sensor in (ALL_SENSORS, r.sensor)
            ]
            if chosen:
                us = np.array([r.us for r in chosen])
                out.append(
                    SummaryRecord(
                        sensor,
                        spec,
                        aggregate(r.score for r in chosen),
                        float(np.median(us)),
                        float(us.mean()),
                        sum(r.nonfinite_lines for r in chosen),
                    )
                )
    return tuple(out)


# --------------------------------------------------------------------------- worst scans


def event_f1(s: ScanScore) -> float:
    """F1 of breakpoints and corners pooled; 1 when nothing counted was true or found."""
    tp = s.breakpoints.tp + s.corners.tp
    wrong = s.breakpoints.fp + s.breakpoints.fn + s.corners.fp + s.corners.fn
    return 2 * tp / (2 * tp + wrong) if 2 * tp + wrong else 1.0


def worst_scans(result: EvalResult, k: int = 4) -> tuple[WorstScan, ...]:
    """The ``k`` scans with the lowest mean event F1 over the specs (see :data:`WORST_BY`).

    Ties go to the scan with more event errors, then to sensor and scene order.
    """
    by_scan: dict[tuple[str, int], list[ScanRecord]] = {}
    for rec in result.records:
        by_scan.setdefault((rec.sensor, rec.scene), []).append(rec)
    ranked = []
    for order, ((sensor, scene), recs) in enumerate(by_scan.items()):
        f1 = np.array([event_f1(r.score) for r in recs])
        errors = sum(
            r.score.breakpoints.fp
            + r.score.breakpoints.fn
            + r.score.corners.fp
            + r.score.corners.fn
            for r in recs
        )
        worst = WorstScan(
            sensor,
            scene,
            recs[0].seed,
            float(f1.mean()),
            tuple((r.spec.label, float(v)) for r, v in zip(recs, f1, strict=True)),
        )
        ranked.append((worst.score, -errors, order, worst))
    ranked.sort(key=lambda item: item[:3])
    return tuple(item[3] for item in ranked[: max(0, k)])


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class EvalConfig:
    """What a run evaluated, stored with its results.

    Attributes
    ----------
    specs:
        The method specs.
    sensors:
        Sensor preset names.
    n:
        Scenes per sensor (the most of any sensor, for a loaded set).
    seed:
        Base seed.
    noise:
        ``"realistic"`` or ``"exact"``.
    tol:
        The tolerances every score was computed with.
    source:
        ``"generated"``, or the scene-set file.
    clutter:
        Whether the scenes are clutter scenes.
    """

    specs: tuple[MethodSpec, ...]
    sensors: tuple[str, ...]
    n: int
    seed: int
    noise: str
    tol: Tolerances = field(default_factory=Tolerances)
    source: str = "generated"
    clutter: bool = False

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (tolerances under ``"tolerances"``)."""
        return {
            "specs": [s.to_dict() for s in self.specs],
            "sensors": list(self.sensors),
            "scenes_per_sensor": self.n,
            "seed": self.seed,
            "noise": self.noise,
            "source": self.source,
            "clutter": self.clutter,
            "scene_seed": "numpy.random.SeedSequence([seed, crc32(sensor), index])"
            ".generate_state(1, uint32)[0]",
            "tolerances": tolerances_dict(self.tol),
        }


@dataclass(frozen=True)
class ScanRecord:
    """The score of one spec on one scan, and its extraction time.

    Attributes
    ----------
    sensor, scene, seed, kind:
        The scene (see :class:`SceneCase`).
    spec:
        The method spec.
    us:
        Wall time of the extraction call, microseconds.
    nonfinite_lines:
        Found segments whose line (``Extraction.lines`` row) is not finite; they
        match nothing and make the environmental similarity NaN.
    score:
        The scores.
    """

    sensor: str
    scene: int
    seed: int
    kind: str
    spec: MethodSpec
    us: float
    nonfinite_lines: int
    score: ScanScore

    def to_dict(self) -> dict[str, Any]:
        """One per-scan CSV row."""
        return {
            "sensor": self.sensor,
            "scene": self.scene,
            "seed": self.seed,
            "kind": self.kind,
            **_spec_columns(self.spec),
            "us": self.us,
            "nonfinite_lines": self.nonfinite_lines,
            **self.score.to_dict(),
        }


@dataclass(frozen=True)
class SummaryRecord:
    """Scores of one spec pooled over the scans of one sensor (or of all)."""

    sensor: str
    spec: MethodSpec
    summary: Summary
    median_us: float
    mean_us: float
    nonfinite_lines: int = 0

    def to_dict(self) -> dict[str, Any]:
        """One summary CSV row."""
        return {
            "sensor": self.sensor,
            **_spec_columns(self.spec),
            "median_us": self.median_us,
            "mean_us": self.mean_us,
            "nonfinite_lines": self.nonfinite_lines,
            **self.summary.to_dict(),
        }


def _spec_columns(spec: MethodSpec) -> dict[str, Any]:
    return {
        "label": spec.label,
        "method": spec.method,
        "preset": spec.preset or "",
        "params": spec.params_text,
    }


@dataclass(frozen=True)
class WorstScan:
    """A scan ranked by :func:`worst_scans`, with each spec's event F1 on it."""

    sensor: str
    scene: int
    seed: int
    score: float
    f1_by_label: tuple[tuple[str, float], ...]


@dataclass(frozen=True, eq=False)
class EvalResult:
    """Per-scan and pooled scores of a run.

    Attributes
    ----------
    config:
        What was evaluated.
    records:
        One per (scene, spec), sensor by sensor, scene by scene, spec by spec.
    summaries:
        One per (sensor, spec), then one per spec pooled over all sensors
        (``sensor == "all"``) when there is more than one sensor.
    scenes:
        The scene set evaluated on, when it was given (else scenes are regenerated
        on demand by :meth:`case`).
    """

    config: EvalConfig
    records: tuple[ScanRecord, ...]
    summaries: tuple[SummaryRecord, ...]
    scenes: SceneSet | None = None

    def summary(self, sensor: str, label: str) -> SummaryRecord:
        """The pooled scores of spec ``label`` on ``sensor`` (or ``"all"``)."""
        for rec in self.summaries:
            if rec.sensor == sensor and rec.spec.label == label:
                return rec
        raise KeyError((sensor, label))

    def per_scan_rows(self) -> list[dict[str, Any]]:
        """Per-scan rows (see :meth:`ScanRecord.to_dict`)."""
        return [r.to_dict() for r in self.records]

    def summary_rows(self) -> list[dict[str, Any]]:
        """Summary rows (see :meth:`SummaryRecord.to_dict`)."""
        return [r.to_dict() for r in self.summaries]

    def to_csv(self, directory: str | Path) -> tuple[Path, Path]:
        """Write ``per_scan.csv`` and ``summary.csv`` into ``directory``.

        Every row carries the tolerances as ``tol_*`` columns.
        """
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        return (
            write_csv(directory / "per_scan.csv", self.per_scan_rows()),
            write_csv(directory / "summary.csv", self.summary_rows()),
        )

    def to_dict(self, *, per_scan: bool = False) -> dict[str, Any]:
        """Config, tolerances, summary rows (and per-scan rows); NaN becomes ``None``."""
        out: dict[str, Any] = {
            "tolerances": tolerances_dict(self.config.tol),
            "config": self.config.to_dict(),
            "worst_by": WORST_BY,
            "summary": self.summary_rows(),
        }
        if per_scan:
            out["per_scan"] = self.per_scan_rows()
        return jsonable(out)

    def to_json(self, path: str | Path, *, per_scan: bool = False) -> Path:
        """Write :meth:`to_dict` to ``path``."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(per_scan=per_scan), indent=2) + "\n")
        return path

    def case(self, sensor: str, index: int) -> SceneCase:
        """Scene ``index`` of ``sensor``: from the scene set, or generated again."""
        if self.scenes is not None:
            return self.scenes.find(sensor, index)
        return make_scene(sensor, index, self.config.seed, self.config.noise, self.config.clutter)

    def table(self, sensor: str) -> list[list[str]]:
        """Formatted :data:`TABLE_COLUMNS` rows of the summaries of ``sensor``."""
        return [
            [rec.spec.label, *(number(fn(rec), fmt) for _, fn, fmt in TABLE_COLUMNS)]
            for rec in self.summaries
            if rec.sensor == sensor
        ]


def tolerances_dict(tol: Tolerances) -> dict[str, Any]:
    """:meth:`Tolerances.to_dict` plus ``alpha_deg``."""
    return tol.to_dict() | {"alpha_deg": math.degrees(tol.alpha)}


def tolerance_caption(tol: Tolerances) -> str:
    """One line stating the tolerances, for table captions and figure titles."""
    return (
        f"tolerances: events +-{tol.event_beams} beams; segments |drho| <= "
        f"{100 * tol.rho:g} cm, |dalpha| <= {math.degrees(tol.alpha):g} deg, overlap >= "
        f"{tol.overlap:g}; don't care: segments < {tol.min_segment_beams} beams, events "
        f"next to runs < {tol.min_run} returns"
        + (", unmatched on curved surfaces" if tol.curved_dont_care else "")
        + (
            ", events the truth marks (junctions, steps and turns the noise hides)"
            if tol.truth_dont_care
            else ""
        )
    )


TABLE_COLUMNS: tuple[tuple[str, Callable[[SummaryRecord], float], str], ...] = (
    ("bp P", lambda r: r.summary.breakpoints.precision, ".3f"),
    ("bp R", lambda r: r.summary.breakpoints.recall, ".3f"),
    ("bp F1", lambda r: r.summary.breakpoints.f1, ".3f"),
    ("corner P", lambda r: r.summary.corners.precision, ".3f"),
    ("corner R", lambda r: r.summary.corners.recall, ".3f"),
    ("corner F1", lambda r: r.summary.corners.f1, ".3f"),
    ("TruePos", lambda r: r.summary.segments.true_pos, ".3f"),
    ("FalsePos", lambda r: r.summary.segments.false_pos, ".3f"),
    ("split", lambda r: r.summary.segments.split, "d"),
    ("merge", lambda r: r.summary.segments.merge, "d"),
    ("|drho| cm", lambda r: 100 * r.summary.segments.mean_abs_drho, ".2f"),
    ("|dalpha| deg", lambda r: math.degrees(r.summary.segments.mean_abs_dalpha), ".2f"),
    ("sim. cm", lambda r: 100 * r.summary.similarity.mean, ".2f"),
    ("accuracy", lambda r: r.summary.accuracy_rate_mean, ".3f"),
    ("us/scan", lambda r: r.median_us, ".0f"),
)
"""Table columns: header, value of a :class:`SummaryRecord`, format. Rates are pooled
(micro-averaged) over the scans; split and merge are totals; ``accuracy`` is the mean
per-scan accuracy rate; ``sim. cm`` the mean environmental-similarity error;
``us/scan`` the median extraction time."""
