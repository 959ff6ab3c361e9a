"""Evaluation over the sensor family: every sensor, and the worst one per metric.

:func:`evaluate_family` runs :func:`~scanlines.evaluation.evaluate.evaluate` on clutter
scenes of the family's sensors (:mod:`scanlines.sim.family`: ``count`` drawn members
and the four corner sensors) with the truth's don't-care events honoured
(:attr:`~scanlines.evaluation.scores.Tolerances.truth_dont_care`) and the truth row
added. :func:`family_rows` reads, per sensor and spec, the four figures of the
family's target, segment figures relative to the truth row of the same sensor (the
ceiling of what any segmentation reaches on those scans):

* breakpoint F1 (target: >= 0.95 on the worst sensor),
* corner F1 (>= 0.90),
* TruePos as a share of the truth row's TruePos (>= 0.97),
* FalsePos minus the truth row's FalsePos (<= 0.05).

:func:`worst_rows` gives, per spec and figure, the worst sensor and its value, and
whether the target holds there.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any

from scanlines.evaluation.evaluate import EvalResult, evaluate
from scanlines.evaluation.scenes import OnScene
from scanlines.evaluation.scores import Tolerances
from scanlines.evaluation.specs import TRUTH, MethodSpec, parse_specs
from scanlines.sim.family import family_names

__all__ = [
    "DEFAULT_FAMILY_COUNT",
    "DEFAULT_FAMILY_SCENES",
    "FIGURES",
    "FamilyRow",
    "WorstRow",
    "evaluate_family",
    "family_rows",
    "worst_rows",
]

DEFAULT_FAMILY_SCENES = 300
"""Scenes per sensor of a family evaluation when none is given."""
DEFAULT_FAMILY_COUNT = 24
"""Drawn sensors (besides the four corners) when none is given."""

FIGURES: tuple[tuple[str, str, str, float], ...] = (
    ("bp_f1", "breakpoint F1", "min", 0.95),
    ("corner_f1", "corner F1", "min", 0.90),
    ("true_pos_ratio", "TruePos / truth row", "min", 0.97),
    ("false_pos_excess", "FalsePos - truth row", "max", 0.05),
)
"""The family's figures: attribute, title, which end is worst, target."""


@dataclass(frozen=True)
class FamilyRow:
    """The family figures of one spec on one sensor."""

    sensor: str
    label: str
    n_scans: int
    bp_f1: float
    corner_f1: float
    true_pos: float
    false_pos: float
    true_pos_ratio: float
    false_pos_excess: float

    def to_dict(self) -> dict[str, Any]:
        """One CSV row."""
        return dict(self.__dict__)


@dataclass(frozen=True)
class WorstRow:
    """The worst sensor of one spec for one figure."""

    label: str
    figure: str
    title: str
    value: float
    sensor: str
    target: float
    met: bool

    def to_dict(self) -> dict[str, Any]:
        """One CSV row."""
        return dict(self.__dict__)


def evaluate_family(
    specs: Iterable[str | MethodSpec],
    count: int = DEFAULT_FAMILY_COUNT,
    n: int = DEFAULT_FAMILY_SCENES,
    seed: int = 0,
    *,
    family_seed: int = 0,
    tol: Tolerances | None = None,
    clutter: bool = True,
    workers: int = 1,
    on_scene: OnScene | None = None,
) -> EvalResult:
    """Evaluate ``specs`` (and the truth row) on ``n`` scenes of every family sensor.

    Parameters
    ----------
    specs:
        Method specs; the truth row is added when missing.
    count, family_seed:
        The family: ``family_sensors(count, family_seed)`` (drawn members, then the
        four corners).
    n, seed:
        Scenes per sensor and their base seed.
    tol:
        Tolerances (defaults when ``None``); ``truth_dont_care`` is turned on.
    clutter:
        Clutter scenes (the default) or the default scenes.
    workers, on_scene:
        As for :func:`~scanlines.evaluation.evaluate.evaluate`.
    """
    parsed = list(parse_specs(specs))
    if not any(s.is_truth for s in parsed):
        parsed.append(MethodSpec(TRUTH))
    tol = replace(Tolerances() if tol is None else tol, truth_dont_care=True)
    return evaluate(
        parsed,
        family_names(count, family_seed),
        n,
        seed,
        tol=tol,
        workers=workers,
        on_scene=on_scene,
        clutter=clutter,
    )


def _truth_label(result: EvalResult) -> str:
    for spec in result.config.specs:
        if spec.is_truth:
            return spec.label
    raise ValueError("the family figures need the truth row: add the spec 'truth'")


def family_rows(result: EvalResult) -> list[FamilyRow]:
    """Per sensor and spec (truth row included), the family figures."""
    truth = _truth_label(result)
    rows = []
    for sensor in result.config.sensors:
        ceiling = result.summary(sensor, truth).summary.segments
        for spec in result.config.specs:
            summary = result.summary(sensor, spec.label).summary
            seg = summary.segments
            rows.append(
                FamilyRow(
                    sensor=sensor,
                    label=spec.label,
                    n_scans=summary.n_scans,
                    bp_f1=summary.breakpoints.f1,
                    corner_f1=summary.corners.f1,
                    true_pos=seg.true_pos,
                    false_pos=seg.false_pos,
                    true_pos_ratio=_ratio(seg.true_pos, ceiling.true_pos),
                    false_pos_excess=seg.false_pos - ceiling.false_pos,
                )
            )
    return rows


def _ratio(a: float, b: float) -> float:
    return a / b if b else math.nan


def worst_rows(rows: Sequence[FamilyRow]) -> list[WorstRow]:
    """Per spec and figure, the worst sensor (NaN figures are skipped)."""
    out = []
    for label in dict.fromkeys(r.label for r in rows):
        mine = [r for r in rows if r.label == label]
        for name, title, end, target in FIGURES:
            valued = [r for r in mine if not math.isnan(getattr(r, name))]
            if not valued:
                continue
            pick = min if end == "min" else max
            worst = pick(valued, key=lambda r, name=name: getattr(r, name))
            value = getattr(worst, name)
            met = value >= target if end == "min" else value <= target
            out.append(WorstRow(label, name, title, value, worst.sensor, target, met))
    return out
