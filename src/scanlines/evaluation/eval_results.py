"""An evaluation's results: what it ran, its scan and summary records, its worst scans."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.evaluation.scenes import SceneCase, SceneSet, make_scene
from scanlines.evaluation.scores import ScanScore, Summary, Tolerances
from scanlines.evaluation.specs import MethodSpec
from scanlines.report import jsonable, number, write_csv

WORST_BY = (
    "event F1: 2 TP / (2 TP + FP + FN) with breakpoints and corners pooled "
    "(1 when the scan has nothing counted), mean over the specs; lowest first"
)
"""How :func:`worst_scans` ranks scans."""

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


COUNT_RATE_CAPTION = (
    "count rate: per scan 1 - (|bp found - bp true| + |corners found - corners true|) / "
    "(bp true + corners true), the paper's Table 3 'accuracy rate', mean over scans; it "
    "compares counts only (a detection in the wrong place is not seen) and is negative "
    "where the count error exceeds the true count"
)
"""The ``count rate`` column's definition, for the footer of a table that shows it."""

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
    ("count rate", lambda r: r.summary.accuracy_rate_mean, ".3f"),
    ("us/scan", lambda r: r.median_us, ".0f"),
)
"""Table columns: header, value of a :class:`SummaryRecord`, format. Rates are pooled
(micro-averaged) over the scans; split and merge are totals; ``count rate`` is the mean
over scans of the paper's count-based accuracy rate (:data:`COUNT_RATE_CAPTION`);
``sim. cm`` the mean environmental-similarity error; ``us/scan`` the median extraction
time."""
