"""The figures of ``RESULTS.md``: the paper's Fig. 13 redone, and the ground-truth bars.

:func:`write_figures` writes them (:data:`FIGURES`) for
:func:`tools.reproduce.reproduce`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from scanlines.evaluation.cases import point_distances
from scanlines.evaluation.evaluate import ALL_SENSORS, EvalResult, tolerance_caption
from scanlines.viz.evaluation import BAR_METRICS, TRUTH_MARK
from scanlines.viz.figures import pyplot, save
from scanlines.viz.scans import SEGMENT_COLOURS, plot_extraction
from tools.reproduce.experiments import (
    FIG13_METHODS,
    PAPER_BOUND,
    ReproduceResult,
    fig13_case,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "BAR_COLOURS",
    "FIGURES",
    "plot_fig13",
    "plot_fig13_frame",
    "plot_ground_truth_bars",
    "write_figures",
]

FIGURES = {
    "fig13": "fig13_similarity.png",
    "frame": "fig13_segments.png",
    "bars": "ground_truth_bars.png",
}
"""Figure files written into ``<out>/figures``."""

DPI = 100


def plot_fig13(result: ReproduceResult) -> Figure:
    """Similarity error along the scan for :data:`FIG13_METHODS` on the chosen frame."""
    plt = pyplot()
    i, case = fig13_case(result)
    n = len(case.scan)
    fig, axes = plt.subplots(len(FIG13_METHODS), 1, figsize=(8, 6.2), sharex=True, sharey=True)
    top = 0.0
    for ax, label in zip(axes, FIG13_METHODS, strict=True):
        extraction = result.labelled.extractions[label][i]
        pieces = point_distances(extraction, case.scan)
        for k, (beams, d) in enumerate(pieces):
            if beams.size:
                order = np.argsort(beams, kind="stable")
                ax.plot(
                    beams[order],
                    100 * d[order],
                    ".-",
                    ms=3,
                    lw=0.8,
                    c=SEGMENT_COLOURS[k % len(SEGMENT_COLOURS)],
                )
                if np.isfinite(d).any():
                    top = max(top, float(100 * np.nanmax(d)))
        ax.axhline(100 * PAPER_BOUND, ls="--", lw=0.8, c="#d62728")
        sim = result.labelled.scores[label][i].similarity
        ax.set_title(
            f"{label}: {len(extraction)} segments, mean {1000 * sim.mean:.1f} mm, "
            f"max {1000 * sim.max_distance:.1f} mm, {sim.n_points} points",
            fontsize=9,
        )
        ax.set_ylabel("distance (cm)", fontsize=8)
        ax.grid(True, lw=0.3)
        ax.tick_params(labelsize=8)
    axes[-1].set_xlabel("beam index", fontsize=8)
    axes[-1].set_xlim(-1, n)
    axes[0].set_ylim(0, max(3.0, min(top * 1.05, 30.0)))
    fig.suptitle(
        f"Similarity error along Intel frame {result.fig13_frame} (shipped excerpt): distance "
        "of each point to its segment's line; one colour per segment; dashed: 2 cm",
        fontsize=9,
    )
    fig.tight_layout()
    return fig


def plot_fig13_frame(result: ReproduceResult) -> Figure:
    """The chosen frame with each Fig. 13 method's segments and the hand labels."""
    plt = pyplot()
    i, case = fig13_case(result)
    lab = case.labels
    points = case.scan.points
    fig, axes = plt.subplots(1, len(FIG13_METHODS), figsize=(4.2 * len(FIG13_METHODS), 4.6))
    for ax, label in zip(axes, FIG13_METHODS, strict=True):
        extraction = result.labelled.extractions[label][i]
        for beams, marker, name in (
            (lab.breakpoints, "o", "labelled breakpoints"),
            (lab.corners, "D", "labelled corners"),
        ):
            if len(beams):
                ax.plot(
                    *points[np.asarray(beams, np.intp)].T,
                    marker,
                    ms=10,
                    c=TRUTH_MARK,
                    alpha=0.5,
                    ls="none",
                    zorder=0,
                    label=name,
                )
        plot_extraction(case.scan, extraction, ax, title=label, legend=False)
        ax.tick_params(labelsize=7)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle(
        f"Intel frame {result.fig13_frame}: segments, breakpoints (red triangles) and corners "
        "(black squares) found; amber: certain hand labels",
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


BAR_COLOURS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)
"""One colour per method in :func:`plot_ground_truth_bars` (matplotlib's tab10)."""


def plot_ground_truth_bars(ev: EvalResult) -> Figure:
    """Section 4 as bars: one panel per sensor preset, :data:`~scanlines.viz.evaluation.BAR_METRICS`
    by method, one distinct colour per method (up to 10)."""
    plt = pyplot()
    sensors = [s for s in dict.fromkeys(r.sensor for r in ev.summaries) if s != ALL_SENSORS]
    specs = ev.config.specs
    cols = 2 if len(sensors) > 1 else 1
    rows = -(-len(sensors) // cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(5.2 * cols, 3.0 * rows + 1.2), squeeze=False, sharey=True
    )
    x = np.arange(len(BAR_METRICS))
    width = 0.85 / len(specs)
    for ax, sensor in zip(axes.flat, sensors, strict=False):
        for j, spec in enumerate(specs):
            summary = ev.summary(sensor, spec.label).summary
            ax.bar(
                x + (j - (len(specs) - 1) / 2) * width,
                [fn(summary) for _, fn in BAR_METRICS],
                width,
                label=spec.label,
                color=BAR_COLOURS[j % len(BAR_COLOURS)],
            )
        n_scans = ev.summary(sensor, specs[0].label).summary.n_scans
        ax.set_title(f"{sensor} ({n_scans} scans)", fontsize=9)
        ax.set_xticks(x, [name for name, _ in BAR_METRICS], fontsize=8)
        ax.set_ylim(0, 1.05)
        ax.tick_params(labelsize=8)
        ax.grid(True, axis="y", lw=0.3)
    for ax in list(axes.flat)[len(sensors) :]:
        ax.axis("off")
    for ax in axes[:, 0]:
        ax.set_ylabel("rate (FalsePos: lower is better)", fontsize=8)
    handles, names = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=min(len(specs), 5), fontsize=8)
    height = 3.0 * rows + 1.2
    fig.suptitle(tolerance_caption(ev.config.tol), fontsize=7)
    fig.tight_layout(rect=(0, 0.75 / height, 1, 1))
    return fig


def write_figures(result: ReproduceResult, folder: str | Path) -> dict[str, Path]:
    """Write the figures (:data:`FIGURES`) into ``folder``; returns key -> path."""
    folder = Path(folder)
    return {
        "fig13": save(plot_fig13(result), folder / FIGURES["fig13"], dpi=DPI),
        "frame": save(plot_fig13_frame(result), folder / FIGURES["frame"], dpi=DPI),
        "bars": save(
            plot_ground_truth_bars(result.ground_truth), folder / FIGURES["bars"], dpi=DPI
        ),
    }
