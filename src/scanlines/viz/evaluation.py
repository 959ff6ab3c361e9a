"""Figures of an evaluation on simulated scans: detections over the truth, bars, worst scans.

:func:`plot_bars` and :func:`plot_worst` draw an
:class:`~scanlines.evaluation.evaluate.EvalResult` (``scanlines eval`` writes them as
``bars.png`` and ``worst.png``); :func:`plot_truth_overlay` draws one scan's detections
over its truth.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from scanlines import Extraction, Scan
from scanlines.evaluation.evaluate import (
    WORST_BY,
    EvalResult,
    extract_case,
    tolerance_caption,
    worst_scans,
)
from scanlines.evaluation.scores import Summary
from scanlines.truth import Truth
from scanlines.viz.figures import pyplot
from scanlines.viz.scans import plot_extraction

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "BAR_METRICS",
    "TRUTH_LINE",
    "TRUTH_MARK",
    "plot_bars",
    "plot_truth_overlay",
    "plot_worst",
]


TRUTH_LINE = "#000000"
TRUTH_MARK = "#ffb000"
"""Colours of the truth: dashed black segments, faint amber event markers."""


def plot_truth_overlay(
    scan: Scan,
    truth: Truth,
    extraction: Extraction,
    ax: Axes | None = None,
    *,
    title: str | None = None,
    legend: bool = True,
) -> Axes:
    """Draw detections (as :func:`scanlines.viz.scans.plot_extraction`) over the truth.

    True segments are thin dashed black lines; true breakpoints (the exact hit point
    of the beam) large faint amber circles; true corners (the vertex) large faint amber
    diamonds. Detections keep their look: solid segments, hollow red triangles
    (breakpoints), hollow black squares (corners). Sensor frame, metres.
    """
    if ax is None:
        _, ax = pyplot().subplots(figsize=(7, 7))
    seg = truth.segments
    xs = np.column_stack((seg.start[:, 0], seg.end[:, 0], np.full(len(seg), np.nan))).ravel()
    ys = np.column_stack((seg.start[:, 1], seg.end[:, 1], np.full(len(seg), np.nan))).ravel()
    ax.plot(xs, ys, "--", c=TRUTH_LINE, lw=1.0, zorder=4, label="true segments")
    bp = truth.hit_points[truth.breakpoints]
    ax.plot(
        *bp.T, "o", ms=13, c=TRUTH_MARK, alpha=0.5, ls="none", zorder=0, label="true breakpoints"
    )
    corners = truth.corner_points
    ax.plot(
        *corners.T,
        "D",
        ms=12,
        c=TRUTH_MARK,
        alpha=0.5,
        ls="none",
        zorder=0,
        label="true corners",
    )
    plot_extraction(scan, extraction, ax, title=title, legend=False)
    if legend:
        ax.legend(loc="best", fontsize=7, markerscale=0.8)
    return ax


def plot_worst(result: EvalResult, k: int = 4, *, size: float = 4.2) -> Figure:
    """The ``k`` worst scans (:func:`~scanlines.evaluation.evaluate.worst_scans`), one row
    each, one column per spec."""
    plt = pyplot()
    worst = worst_scans(result, k)
    specs = result.config.specs
    rows, cols = max(1, len(worst)), len(specs)
    width, height = max(size * cols, 7.0), size * rows + 1.6  # 1.6 in: title and legend
    fig, axes = plt.subplots(rows, cols, figsize=(width, height), squeeze=False)
    for row, item in zip(axes, worst, strict=False):
        case = result.case(item.sensor, item.scene)
        for ax, spec, (_, f1) in zip(row, specs, item.f1_by_label, strict=True):
            title = f"{spec.label} | {item.sensor} #{item.scene} ({case.kind})\nevent F1 {f1:.2f}"
            found = extract_case(spec, case)
            plot_truth_overlay(case.scan, case.truth, found, ax, title=title, legend=False)
    if not worst:
        for ax in axes.flat:
            ax.axis("off")
    handles, labels = _overlay_legend(axes)
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    text = f"Worst {len(worst)} scans by {WORST_BY}. {tolerance_caption(result.config.tol)}"
    fig.suptitle(_wrapped(text, width), fontsize=8)
    fig.tight_layout(rect=(0, 0.8 / height, 1, 1 - 0.8 / height))
    return fig


def _wrapped(text: str, width_inches: float) -> str:
    """``text`` broken into lines that fit a figure ``width_inches`` wide at 8 pt."""
    return textwrap.fill(text, width=max(40, int(15 * width_inches)))


def _overlay_legend(axes: np.ndarray) -> tuple[list[Any], list[str]]:
    seen: dict[str, Any] = {}
    for ax in axes.flat:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(label, handle)
    return list(seen.values()), list(seen)


BAR_METRICS: tuple[tuple[str, Callable[[Summary], float]], ...] = (
    ("breakpoint F1", lambda s: s.breakpoints.f1),
    ("corner F1", lambda s: s.corners.f1),
    ("segment TruePos", lambda s: s.segments.true_pos),
    ("segment FalsePos", lambda s: s.segments.false_pos),
)
"""The metrics of :func:`plot_bars`."""


def plot_bars(result: EvalResult, *, size: float = 4.0) -> Figure:
    """Grouped bars per sensor: :data:`BAR_METRICS` (groups) by spec (bars)."""
    plt = pyplot()
    palette = plt.get_cmap("tab20").colors  # one colour per spec, up to 20
    sensors = list(dict.fromkeys(r.sensor for r in result.summaries))
    specs = result.config.specs
    fig, axes = plt.subplots(
        1, len(sensors), figsize=(size * len(sensors), size), squeeze=False, sharey=True
    )
    x = np.arange(len(BAR_METRICS))
    width = 0.8 / len(specs)
    for ax, sensor in zip(axes[0], sensors, strict=True):
        for j, spec in enumerate(specs):
            summary = result.summary(sensor, spec.label).summary
            values = [fn(summary) for _, fn in BAR_METRICS]
            ax.bar(
                x + (j - (len(specs) - 1) / 2) * width,
                values,
                width,
                label=spec.label,
                color=palette[j % len(palette)],
            )
        n_scans = result.summary(sensor, specs[0].label).summary.n_scans
        ax.set_title(f"{sensor} ({n_scans} scans)", fontsize=10)
        ax.set_xticks(x, [name for name, _ in BAR_METRICS], rotation=25, ha="right", fontsize=8)
        ax.set_ylim(0, 1.05)
        ax.grid(True, axis="y", lw=0.3)
    axes[0, 0].set_ylabel("rate (FalsePos: lower is better)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(_wrapped(tolerance_caption(result.config.tol), size * len(sensors)), fontsize=8)
    fig.tight_layout()
    return fig
