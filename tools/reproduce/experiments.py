"""The paper's experiments (sec. 4), measured on the data scanlines ships.

Everything here runs on what the repository holds: the two real excerpts of
:mod:`scanlines.data` (Intel Research Lab, Freiburg 079), the hand labels of ten Intel
frames (:mod:`scanlines.data.labels`) and the scan simulator (:mod:`scanlines.sim`).
:func:`run` measures; :mod:`tools.reproduce.results_page` writes the page and
:mod:`tools.reproduce.figures` its figures (:func:`tools.reproduce.reproduce`
does all three).

What is measured
----------------
1. **Table 1** of the paper (breakpoints and corners of 10 Intel frames): on the
   hand-labelled Intel frames and on simulated Intel-like scans (``lms_1deg``), per
   frame and method, the actual and found counts, and matched precision and recall.
2. **Table 3** (counts, the paper's count-based accuracy rate, time per scan): on
   simulated scans of the paper's sensor (``tim571``) and on the labelled Intel frames,
   with matched precision and recall; on all shipped scans of both real excerpts
   (no labels): counts per scan, the environmental-similarity error and time.
3. **Fig. 13** (similarity error along the scan) for adaptive, IEPF and PDBS on one
   labelled Intel frame, the frame with each method's segments, and the paper's two
   headline claims measured on the same scans in one run: the similarity error of
   adaptive against IEPF (the paper: 8.3 % better) and the speed ratio (the paper: four
   times faster).
4. Every method on simulated ground truth for every sensor preset
   (:func:`scanlines.evaluation.evaluate.evaluate`).

Sensor profiles
---------------
Every method extracts the real excerpts (and the labelled Intel frames) with one sensor
profile measured from the whole excerpt, as ``scanlines run`` and ``scanlines eval
--labels`` do; simulated scans measure their own noise, as ``scanlines eval`` does.

Matching
--------
Found events are matched one-to-one to true or labelled ones within
``Tolerances.event_beams`` beams (2), nearest pairs first
(:func:`~scanlines.evaluation.cases.score_labelled`). Uncertain hand labels are don't
care: a detection matched to one is neither a true nor a false positive, and missing one
is not a false negative. Simulated truth uses :func:`scanlines.evaluation.metrics.score`
with its own don't-care rules (see :class:`~scanlines.evaluation.scores.Tolerances`).

Timing
------
All timings are taken in one process by :mod:`scanlines.bench.timing`: per dataset,
``repeats`` passes over every scan, interleaved between methods, every timed extraction
directly after an untimed one of the same scan by the same method (whose result is the
one scored). Reported: the median (and 90th percentile) of the samples, microseconds per
scan; per scan, the median of its samples. Section 4 uses
:func:`~scanlines.evaluation.evaluate.evaluate`'s one pass per scene.
"""

from __future__ import annotations

import datetime as _dt
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from scanlines import Extraction, ParameterError, Scan, method_names
from scanlines.bench.machine import load_average, machine_info
from scanlines.bench.timing import REFERENCE, time_calls
from scanlines.evaluation.cases import Case, FrameScore, LabelledFrameLike, score_case
from scanlines.evaluation.evaluate import EvalResult, evaluate
from scanlines.evaluation.scenes import make_scene
from scanlines.evaluation.scores import EventScore, SimilarityScore, Tolerances
from scanlines.evaluation.specs import MethodSpec, parse_specs
from scanlines.sensor.profile import SensorProfile, estimate_profile
from scanlines.sim import SENSORS

__all__ = [
    "FIG13_METHODS",
    "FIG13_RULE",
    "PAPER_BOUND",
    "PAPER_SIMILARITY_GAIN",
    "PAPER_SPEED_RATIO",
    "REAL_EXCERPTS",
    "DatasetRun",
    "Headline",
    "MethodSummary",
    "ReproduceConfig",
    "ReproduceResult",
    "default_specs",
    "fig13_case",
    "headline",
    "load_labels",
    "run",
    "run_dataset",
]

PAPER_SIMILARITY_GAIN = 8.3
"""The paper's claim: its method's similarity is 8.3 % better than IEPF's (sec. 4.4)."""

PAPER_SPEED_RATIO = 4.0
"""The paper's claim: its method is four times faster than IEPF (sec. 4.5, Table 3)."""

FIG13_METHODS = ("adaptive", "iepf", "pdbs")
"""The methods of the paper's Fig. 13 (its method, IEPF, PDBS)."""

PAPER_BOUND = 0.02
"""The paper's bound on its method's similarity error, metres (sec. 4.4)."""

REAL_EXCERPTS = {
    "intel": "Intel Research Lab excerpt (SICK LMS, 180 beams at 1 deg), no labels",
    "freiburg": "Freiburg 079 excerpt (SICK LMS, 360 beams at 0.5 deg), no labels",
}
"""The shipped real excerpts (``scanlines.data.sample`` names) and what they are."""

Stage = Callable[[str], None]
"""``on_stage(text)``: called when a stage of :func:`run` starts."""


# --------------------------------------------------------------------------- configuration


@dataclass(frozen=True)
class ReproduceConfig:
    """What :func:`run` measures.

    Parameters
    ----------
    scenes_per_sensor:
        Simulated scenes per sensor preset for section 4.
    table_scenes:
        Simulated scenes for the Table 1 (``lms_1deg``) and Table 3 (``tim571``) analogues.
    frames:
        Labelled Intel frames used (the first ones); ``None``: all.
    real_scans:
        Scans of each real excerpt for the unlabelled Table 3 and the headline; ``None``:
        all shipped scans.
    repeats:
        Timed passes per dataset.
    seed:
        Base seed of the simulated scenes (:func:`scanlines.evaluation.scenes.scene_seed`).
    tol:
        Matching tolerances.
    jobs:
        Processes scoring the simulated scenes (the timed passes always run in one).
    quick:
        Recorded in the output (set by :meth:`quick_config`).
    """

    scenes_per_sensor: int = 100
    table_scenes: int = 10
    frames: int | None = None
    real_scans: int | None = None
    repeats: int = 5
    seed: int = 0
    tol: Tolerances = field(default_factory=Tolerances)
    jobs: int = 1
    quick: bool = False

    @classmethod
    def quick_config(cls, **changes: Any) -> ReproduceConfig:
        """A small run for tests: 3 scenes, 2 labelled frames, 20 real scans, 1 repeat."""
        base = cls(scenes_per_sensor=3, table_scenes=3, frames=2, real_scans=20, repeats=1)
        return replace(base, quick=True, **changes)

    def validated(self) -> ReproduceConfig:
        """This configuration, checked.

        Raises
        ------
        ParameterError
            For a count below 1 or a negative seed.
        """
        for name in ("scenes_per_sensor", "table_scenes", "repeats", "jobs"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ParameterError(f"{name.replace('_', ' ')} must be an integer >= 1")
        for name in ("frames", "real_scans"):
            value = getattr(self, name)
            if value is not None and (not isinstance(value, int) or value < 1):
                raise ParameterError(f"{name.replace('_', ' ')} must be an integer >= 1")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ParameterError(f"seed must be an integer >= 0, got {self.seed!r}")
        return self


def default_specs() -> tuple[MethodSpec, ...]:
    """Every registered method with default parameters, and ``adaptive:paper`` after adaptive."""
    names: list[str] = []
    for name in method_names():
        names.append(name)
        if name == "adaptive":
            names.append("adaptive:paper")
    return parse_specs(names)


def load_labels() -> list[LabelledFrameLike]:
    """The hand labels of the shipped Intel frames (``scanlines.data.labels.intel_labels``).

    Raises
    ------
    ParameterError
        When the labels are not installed.
    """
    try:
        from scanlines.data.labels import intel_labels
    except ImportError as error:
        raise ParameterError(
            f"the Intel hand labels (scanlines.data.labels) are not available: {error}"
        ) from None
    return list(intel_labels())


def _label_metadata() -> tuple[str, str]:
    """The labelling rule and how the frames were chosen, as the label file states them."""
    try:
        from scanlines.data.labels import intel_label_set

        label_set = intel_label_set()
    except ImportError:
        return "", ""
    return str(label_set.rule), str(label_set.how_chosen)


# --------------------------------------------------------------------------- running


@dataclass(frozen=True)
class MethodSummary:
    """One method pooled over the scans of one dataset.

    Event scores and the similarity are summed over scans (micro-averages); counts are
    totals; times are the median and 90th percentile of all samples, microseconds.
    """

    label: str
    n_scans: int
    n_segments: int
    bp_found: int
    c_found: int
    bp_actual: int | None
    c_actual: int | None
    bp: EventScore | None
    corners: EventScore | None
    accuracy_mean: float
    accuracy_pooled: float
    similarity: SimilarityScore
    covered_points: int
    nonfinite_lines: int
    valid_points: int
    median_us: float
    p90_us: float

    @property
    def coverage(self) -> float:
        """Share of valid returns on a segment with a finite line (seen by the similarity)."""
        return self.covered_points / self.valid_points if self.valid_points else math.nan


@dataclass(frozen=True, eq=False)
class DatasetRun:
    """Every method on every scan of one dataset: extractions, scores and timings.

    Attributes
    ----------
    name:
        Short name (``"intel-labelled"``, ``"sim:tim571"``, ``"freiburg"``...).
    title:
        What the scans are.
    cases:
        The scans (with their truth).
    specs:
        The method specs.
    extractions:
        ``label -> one extraction per case`` (from the untimed pass).
    scores:
        ``label -> one score per case``.
    samples_ns:
        ``label -> (repeats, cases)`` timing samples, nanoseconds.
    """

    name: str
    title: str
    cases: tuple[Case, ...]
    specs: tuple[MethodSpec, ...]
    extractions: dict[str, list[Extraction]]
    scores: dict[str, list[FrameScore]]
    samples_ns: dict[str, np.ndarray]

    @property
    def labels(self) -> tuple[str, ...]:
        """The spec labels, in order."""
        return tuple(s.label for s in self.specs)

    def per_scan_us(self, label: str) -> np.ndarray:
        """Median time of every scan, microseconds."""
        return np.median(self.samples_ns[label], axis=0) / 1000.0

    def summary(self, label: str) -> MethodSummary:
        """The pooled scores and times of ``label``."""
        rows = self.scores[label]
        us = self.samples_ns[label].ravel() / 1000.0
        has_truth = rows[0].bp is not None
        rates = np.array([r.accuracy for r in rows], dtype=np.float64)
        finite = rates[np.isfinite(rates)]
        bp_actual = sum(r.bp_actual or 0 for r in rows) if has_truth else None
        c_actual = sum(r.c_actual or 0 for r in rows) if has_truth else None
        diff = sum(
            abs(r.bp_found - (r.bp_actual or 0)) + abs(r.c_found - (r.c_actual or 0)) for r in rows
        )
        total = (bp_actual or 0) + (c_actual or 0)
        return MethodSummary(
            label=label,
            n_scans=len(rows),
            n_segments=sum(r.n_segments for r in rows),
            bp_found=sum(r.bp_found for r in rows),
            c_found=sum(r.c_found for r in rows),
            bp_actual=bp_actual,
            c_actual=c_actual,
            bp=sum((r.bp for r in rows if r.bp is not None), EventScore()) if has_truth else None,
            corners=sum((r.corners for r in rows if r.corners is not None), EventScore())
            if has_truth
            else None,
            accuracy_mean=float(finite.mean()) if finite.size else math.nan,
            accuracy_pooled=1.0 - diff / total if has_truth and total else math.nan,
            similarity=sum((r.similarity for r in rows), SimilarityScore()),
            covered_points=sum(r.covered_points for r in rows),
            nonfinite_lines=sum(r.nonfinite_lines for r in rows),
            valid_points=sum(r.valid_points for r in rows),
            median_us=float(np.median(us)) if us.size else math.nan,
            p90_us=float(np.percentile(us, 90)) if us.size else math.nan,
        )

    def time_ratio(self, label: str, reference: str = REFERENCE) -> float:
        """Median time of ``label`` over that of ``reference`` (below 1: faster)."""
        if reference not in self.samples_ns:
            return math.nan
        return self.summary(label).median_us / self.summary(reference).median_us


def run_dataset(
    name: str,
    title: str,
    cases: Sequence[Case],
    specs: Sequence[MethodSpec],
    *,
    repeats: int,
    tol: Tolerances,
    sensor_profile: SensorProfile | None = None,
) -> DatasetRun:
    """Run, time and score every spec on every case (see the module docstring, Timing),
    each spec with ``sensor_profile`` (``None``: each scan measures its own noise)."""
    if not cases:
        raise ParameterError(f"dataset {name} has no scans")
    extractors = {s.label: s.extractor(sensor_profile) for s in specs}
    timed = time_calls(extractors, [c.scan for c in cases], repeats)
    extractions = {label: t.results for label, t in timed.items()}
    samples = {label: t.samples_ns for label, t in timed.items()}
    scores = {
        label: [score_case(c, label, e, tol) for c, e in zip(cases, found, strict=True)]
        for label, found in extractions.items()
    }
    return DatasetRun(name, title, tuple(cases), tuple(specs), extractions, scores, samples)


@dataclass(frozen=True)
class Headline:
    """The paper's two claims, measured on one dataset in one run.

    Attributes
    ----------
    dataset:
        Dataset name.
    n_scans:
        Scans measured.
    method, reference:
        Spec labels compared (``adaptive`` against ``iepf``).
    similarity_mm, reference_similarity_mm:
        Mean point-to-line distance (environmental similarity error) over all points of
        all segments of all scans, millimetres.
    similarity_gain_pct:
        ``100 (reference - method) / reference``: how much smaller the method's error is
        (positive: the method is better; the paper claims +8.3 %).
    median_us, reference_median_us:
        Median time per scan, microseconds.
    speed_ratio:
        ``reference time / method time``: above 1 the method is faster (the paper
        claims 4).
    """

    dataset: str
    n_scans: int
    method: str
    reference: str
    similarity_mm: float
    reference_similarity_mm: float
    similarity_gain_pct: float
    median_us: float
    reference_median_us: float
    speed_ratio: float


def headline(run: DatasetRun, method: str = "adaptive", reference: str = REFERENCE) -> Headline:
    """Similarity gain (%) and speed ratio of ``method`` against ``reference`` on ``run``."""
    a, b = run.summary(method), run.summary(reference)
    sim_a, sim_b = 1000 * a.similarity.mean, 1000 * b.similarity.mean
    return Headline(
        dataset=run.name,
        n_scans=len(run.cases),
        method=method,
        reference=reference,
        similarity_mm=sim_a,
        reference_similarity_mm=sim_b,
        similarity_gain_pct=100.0 * (sim_b - sim_a) / sim_b if sim_b else math.nan,
        median_us=a.median_us,
        reference_median_us=b.median_us,
        speed_ratio=b.median_us / a.median_us if a.median_us else math.nan,
    )


@dataclass(frozen=True, eq=False)
class ReproduceResult:
    """Everything one :func:`run` measured."""

    config: ReproduceConfig
    specs: tuple[MethodSpec, ...]
    labelled: DatasetRun
    sim_table1: DatasetRun
    sim_table3: DatasetRun
    real: tuple[DatasetRun, ...]
    ground_truth: EvalResult
    fig13_frame: int
    machine: dict[str, Any]
    started: str
    elapsed_s: float
    command: str
    label_notes: dict[int, str] = field(default_factory=dict)
    label_rule: str = ""
    label_how_chosen: str = ""

    def headlines(self, method: str = "adaptive") -> list[Headline]:
        """:func:`headline` of ``method`` on every real excerpt."""
        return [headline(r, method) for r in self.real]


def _sim_cases(sensor: str, n: int, seed: int) -> list[Case]:
    out = []
    for i in range(n):
        scene = make_scene(sensor, i, seed)
        out.append(Case(f"{sensor} #{i}", scene.scan, truth=scene.truth))
    return out


def _real_scans(name: str) -> list[Scan]:
    from scanlines.data import sample
    from scanlines.io import open_log

    return list(open_log(sample(name)))


FIG13_RULE = (
    "the labelled frame with the most certain corners, then the most certain breakpoints, "
    "then the lowest scan index"
)
"""How :func:`run` picks the Fig. 13 frame."""


def _choose_fig13_frame(labels: Sequence[LabelledFrameLike]) -> int:
    """The frame :data:`FIG13_RULE` picks."""
    best = max(labels, key=lambda f: (len(f.corners), len(f.breakpoints), -f.scan))
    return int(best.scan)


def run(
    config: ReproduceConfig | None = None,
    *,
    labels: Sequence[LabelledFrameLike] | None = None,
    specs: Sequence[str | MethodSpec] | None = None,
    command: str = "python -m tools.reproduce",
    on_stage: Stage | None = None,
) -> ReproduceResult:
    """Measure everything ``RESULTS.md`` shows (see the module docstring).

    Parameters
    ----------
    config:
        What to measure; :class:`ReproduceConfig` defaults when ``None``.
    labels:
        Hand-labelled Intel frames; :func:`load_labels` when ``None``.
    specs:
        Method specs; :func:`default_specs` when ``None`` (must include ``adaptive``,
        ``iepf`` and ``pdbs``).
    command:
        The command line recorded in the output.
    on_stage:
        Called with a short text when a stage starts.

    Raises
    ------
    ParameterError
        For a bad configuration, missing labels, a label outside the Intel excerpt or
        specs without adaptive, iepf and pdbs.
    """
    config = (config or ReproduceConfig()).validated()
    parsed = default_specs() if specs is None else parse_specs(specs)
    missing = [m for m in FIG13_METHODS if m not in {s.label for s in parsed}]
    if missing:
        raise ParameterError(f"the specs must include {', '.join(missing)}")
    stage = on_stage or (lambda _text: None)
    started = _dt.datetime.now(_dt.UTC).replace(microsecond=0)
    t0 = time.perf_counter()
    machine = machine_info()
    tol = config.tol
    intel = _real_scans("intel")
    frames, rule, how_chosen = _labelled_frames(labels, config.frames, len(intel))

    def dataset(
        name: str, title: str, cases: Sequence[Case], profile: SensorProfile | None = None
    ) -> DatasetRun:
        return run_dataset(
            name, title, cases, parsed, repeats=config.repeats, tol=tol, sensor_profile=profile
        )

    def profile_of(name: str, scans: Sequence[Scan]) -> SensorProfile:
        return estimate_profile(scans, source=f"shipped {name} excerpt")

    stage(f"Table 1: {len(frames)} labelled Intel frames")
    labelled = dataset(
        "intel-labelled",
        "hand-labelled frames of the shipped Intel excerpt (SICK LMS, 180 beams at 1 deg)",
        [Case(f"intel #{f.scan}", intel[f.scan], labels=f) for f in frames],
        profile_of("intel", intel),
    )
    stage(f"Table 1: {config.table_scenes} simulated lms_1deg scenes")
    sim_table1 = dataset(
        "sim:lms_1deg",
        "simulated Intel-like scans (lms_1deg preset), simulator ground truth",
        _sim_cases("lms_1deg", config.table_scenes, config.seed),
    )
    stage(f"Table 3: {config.table_scenes} simulated tim571 scenes")
    sim_table3 = dataset(
        "sim:tim571",
        "simulated scans of the paper's sensor (tim571 preset: 481 beams at 1/3 deg), "
        "simulator ground truth",
        _sim_cases("tim571", config.table_scenes, config.seed),
    )
    real = []
    for name in REAL_EXCERPTS:
        excerpt = intel if name == "intel" else _real_scans(name)
        scans = excerpt[: config.real_scans]
        stage(f"Table 3 and headline: {len(scans)} {name} scans x {config.repeats} repeats")
        cases = [Case(f"{name} #{i}", s) for i, s in enumerate(scans)]
        real.append(dataset(name, REAL_EXCERPTS[name], cases, profile_of(name, excerpt)))
    stage(f"Ground truth: {config.scenes_per_sensor} scenes x {len(SENSORS)} sensor presets")
    ground_truth = evaluate(
        parsed, None, config.scenes_per_sensor, config.seed, tol=tol, workers=config.jobs
    )
    machine["loadavg_after"] = load_average()
    return ReproduceResult(
        config=config,
        specs=parsed,
        labelled=labelled,
        sim_table1=sim_table1,
        sim_table3=sim_table3,
        real=tuple(real),
        ground_truth=ground_truth,
        fig13_frame=_choose_fig13_frame(frames),
        machine=machine,
        started=started.isoformat(),
        elapsed_s=time.perf_counter() - t0,
        command=command,
        label_notes={int(f.scan): str(getattr(f, "notes", "") or "") for f in frames},
        label_rule=rule,
        label_how_chosen=how_chosen,
    )


def _labelled_frames(
    labels: Sequence[LabelledFrameLike] | None, first: int | None, n_intel: int
) -> tuple[list[LabelledFrameLike], str, str]:
    """The first ``first`` frames (by scan index; all when ``None``) of ``labels`` or the
    shipped labels, with the labelling rule and how the frames were chosen (shipped only).
    """
    rule = how_chosen = ""
    if labels is None:
        frames = load_labels()
        rule, how_chosen = _label_metadata()
    else:
        frames = list(labels)
    if not frames:
        raise ParameterError("no labelled Intel frames")
    frames = sorted(frames, key=lambda f: f.scan)[:first]
    for f in frames:
        if not 0 <= f.scan < n_intel:
            raise ParameterError(
                f"labelled frame {f.scan} is outside the Intel excerpt (0..{n_intel - 1})"
            )
    return frames, rule, how_chosen


def fig13_case(result: ReproduceResult) -> tuple[int, Case]:
    """The Fig. 13 frame of ``result`` (:data:`FIG13_RULE`): its position and case."""
    run_ = result.labelled
    for i, case in enumerate(run_.cases):
        if case.labels is not None and int(case.labels.scan) == result.fig13_frame:
            return i, case
    raise KeyError(result.fig13_frame)
