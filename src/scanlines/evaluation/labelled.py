"""Scores on the hand-labelled frames of the shipped real logs, and how whole their walls are.

For each labelled sample (:func:`scanlines.data.labels.labelled_samples`: SICK at 1 deg,
SICK at 0.5 deg, URG-04LX) every method spec runs on the labelled frames; found
breakpoints and corners are matched to the labels as
:func:`scanlines.evaluation.cases.score_labelled` does (uncertain labels don't care).
As ``scanlines run`` does, each spec uses one sensor profile measured from the whole
excerpt. On every scan of the excerpt (labelled or not) the table also reports how
whole the segments are: segments per scan, their median length, the share with fewer
than five returns, and the coverage (share of returns on a segment)::

    from scanlines.evaluation.labelled import evaluate_labelled
    result = evaluate_labelled(["adaptive", "iepf"])
    result.rows()
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.evaluation.cases import score_labelled
from scanlines.evaluation.scores import EventScore
from scanlines.evaluation.specs import MethodSpec, parse_specs
from scanlines.extraction import END_X, END_Y, START_X, START_Y, Extraction
from scanlines.report import write_csv
from scanlines.scan import Scan
from scanlines.sensor.profile import SensorProfile, estimate_profile

__all__ = ["LabelledResult", "LabelledRow", "evaluate_labelled", "fragmentation"]

SHORT_RETURNS = 5
"""Segments with fewer returns than this count as short pieces."""


@dataclass(frozen=True)
class Fragmentation:
    """How whole the segments of a set of scans are."""

    segments_per_scan: float
    median_length: float
    short_share: float
    coverage: float


def fragmentation(scans: Sequence[Scan], extractions: Sequence[Extraction]) -> Fragmentation:
    """Segments per scan, median length (m; segments with a line), share under
    :data:`SHORT_RETURNS` returns, and the share of valid returns on a segment (each
    return counted once, outliers not)."""
    lengths, counts = [], []
    covered = valid = 0
    for scan, extraction in zip(scans, extractions, strict=True):
        lines = extraction.lines
        lengths.append(
            np.hypot(lines[:, END_X] - lines[:, START_X], lines[:, END_Y] - lines[:, START_Y])
        )
        counts.append(extraction.n_points)
        covered += int(np.count_nonzero(_on_segments(scan, extraction)))
        valid += int(scan.valid.sum())
    length, count = np.concatenate(lengths), np.concatenate(counts)
    length = length[np.isfinite(length)]
    return Fragmentation(
        segments_per_scan=count.size / max(len(scans), 1),
        median_length=float(np.median(length)) if length.size else math.nan,
        short_share=float(np.mean(count < SHORT_RETURNS)) if count.size else math.nan,
        coverage=covered / valid if valid else math.nan,
    )


def _on_segments(scan: Scan, extraction: Extraction) -> np.ndarray:
    """Mask of the valid returns inside some segment's beam span (not outliers)."""
    n = len(scan)
    on = np.zeros(n, dtype=bool)
    for first, last in zip(extraction.first, extraction.last, strict=True):
        if first <= last:
            on[first : last + 1] = True
        else:  # across the seam of a full circle
            on[first:] = True
            on[: last + 1] = True
    on[extraction.outliers] = False
    return on & scan.valid


@dataclass(frozen=True)
class LabelledRow:
    """One spec on one labelled sample."""

    sample: str
    label: str
    frames: int
    breakpoints: EventScore
    corners: EventScore
    whole: Fragmentation

    def values(self) -> dict[str, Any]:
        """The row as named numbers (for tables, CSV and JSON)."""
        bp, c, w = self.breakpoints, self.corners, self.whole
        return {
            "sample": self.sample,
            "method": self.label,
            "frames": self.frames,
            "bp_P": bp.precision,
            "bp_R": bp.recall,
            "bp_F1": bp.f1,
            "corner_P": c.precision,
            "corner_R": c.recall,
            "corner_F1": c.f1,
            "segments_per_scan": w.segments_per_scan,
            "median_length_m": w.median_length,
            "short_share": w.short_share,
            "coverage": w.coverage,
        }


@dataclass
class LabelledResult:
    """Every spec on every labelled sample."""

    rows_: list[LabelledRow] = field(default_factory=list)
    tolerance: int = 2

    def rows(self) -> list[dict[str, Any]]:
        return [row.values() for row in self.rows_]

    def to_csv(self, path: str | Path) -> Path:
        return write_csv(Path(path), self.rows())


def evaluate_labelled(
    specs: Iterable[str | MethodSpec],
    samples: Iterable[str] | None = None,
    *,
    tolerance: int = 2,
    sensor_profile: SensorProfile | None = None,
    on_progress: Callable[[int, int], None] | None = None,
) -> LabelledResult:
    """Score ``specs`` on the hand-labelled frames of ``samples`` (default: every one),
    with ``sensor_profile`` (``None``: one measured from each excerpt);
    ``on_progress(done, total)`` after each (sample, spec) scored."""
    from scanlines.data import sample
    from scanlines.data.labels import label_log_options, label_set, labelled_samples
    from scanlines.io import open_log

    result = LabelledResult(tolerance=tolerance)
    specs = parse_specs(specs)
    names = list(samples or labelled_samples())
    for name in names:
        labels = label_set(name)
        options = label_log_options(name, labels.angle_convention)
        scans = list(open_log(sample(name), **options))
        profile = sensor_profile or estimate_profile(scans, source=sample(name).name)
        for spec in specs:
            result.rows_.append(_score(name, spec, scans, labels.frames, profile, tolerance))
            if on_progress is not None:
                on_progress(len(result.rows_), len(names) * len(specs))
    return result


def _score(
    name: str,
    spec: MethodSpec,
    scans: list[Scan],
    frames: Sequence[Any],
    profile: SensorProfile,
    tolerance: int,
) -> LabelledRow:
    extractor = spec.extractor(sensor_profile=profile)
    extractions = [extractor(scan) for scan in scans]
    bp, corners = EventScore(), EventScore()
    for frame in frames:
        found, n_beams = extractions[frame.scan], len(scans[frame.scan])
        bp = bp + score_labelled(
            found.breakpoints, frame.breakpoints, frame.uncertain_breakpoints,
            tolerance=tolerance, n_beams=n_beams,
        )  # fmt: skip
        corners = corners + score_labelled(
            found.corners, frame.corners, frame.uncertain_corners,
            tolerance=tolerance, n_beams=n_beams,
        )  # fmt: skip
    whole = fragmentation(scans, extractions)
    return LabelledRow(name, spec.label, len(frames), bp, corners, whole)
