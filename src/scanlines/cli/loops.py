"""The loop-closed map of ``scanlines map --align``: progress, the closures' report and plot."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from scanlines.reader_options import ReaderOptions


def run_closed_build(
    log: Path, options: ReaderOptions, prepared: dict[str, Any], scans: str | None
):
    """The tracked map with its loops closed (:mod:`scanlines.map.loopmap`), with a
    progress bar on a terminal: the scans tracked, then the closures searched."""
    from scanlines.cli.progress import progress
    from scanlines.io import open_log
    from scanlines.map.loopmap import build_closed_map
    from scanlines.reader_options import parse_scans, select_scans
    from scanlines.runs.runner import selected_count

    selection = parse_scans(scans)
    with open_log(log, options=options) as reader:
        total = selected_count(reader.scans_in_file, selection)
        with progress(f"tracking and mapping {log.name}", total) as tick:

            def on_query(done: int, total: int) -> None:
                tick.stage(f"closing loops of {log.name}", done, total)

            return build_closed_map(
                select_scans(reader.enumerate(), selection), prepared["extractor"],
                poses=prepared["poses"], settings=prepared["settings"], track=prepared["track"],
                source=str(log), on_scan=tick.scan, on_query=on_query,
            )  # fmt: skip


def report_loops(summary: dict[str, Any]) -> None:
    """The closures accepted (a table: both scans, the correction each made, its fit) and
    the candidates refused, by reason."""
    from rich.box import SIMPLE_HEAD
    from rich.console import Console
    from rich.table import Table

    solver = summary["solver"]
    refused = ", ".join(f"{n} {why}" for why, n in sorted(summary["refused"].items()))
    typer.echo(
        f"loops: {summary['accepted']} closures accepted of {summary['candidates']} candidates"
        f" (refused: {refused or 'none'}); pose graph of {solver.get('poses', 0)} poses and "
        f"{solver.get('edges', 0)} edges optimised in {solver.get('seconds', 0.0):.2f} s; "
        f"poses moved by median {1000 * summary['moved_m']['median']:.0f} mm, max "
        f"{1000 * summary['moved_m']['max']:.0f} mm"
    )
    if not summary["closures"]:
        return
    table = Table(title="loop closures", box=SIMPLE_HEAD)
    for column in ("old scan", "scan", "correction, m", "deg", "inliers", "rms, mm", "chi2"):
        table.add_column(column, justify="right")
    for c in summary["closures"]:
        table.add_row(
            str(c["scan_i"]), str(c["scan_j"]), f"{c['correction_m']:.3f}",
            f"{c['correction_deg']:.2f}", f"{c['inliers']:.2f}", f"{1000 * c['rms']:.1f}",
            f"{c['mahalanobis']:.1f}",
        )  # fmt: skip
    Console().print(table)


def plot_closed(lines, build, closed, title: str):
    """The map with the optimised trajectory and each closure drawn between its scans."""
    import numpy as np

    from scanlines.viz.maps import plot_map

    origin = np.array(build.frame.origin[:2])
    path = closed.poses[:, :2] + origin
    ax = plot_map(lines, title=f"{title}: {len(closed.closures)} loop closures", trajectory=path)
    for k, c in enumerate(closed.closures):
        a, b = path[c.node_i], path[c.node_j]
        ax.plot([a[0], b[0]], [a[1], b[1]], c="tab:red", lw=0.8, zorder=3,
                label="loop closure" if k == 0 else None)  # fmt: skip
        ax.plot([a[0], b[0]], [a[1], b[1]], "o", c="tab:red", ms=2, zorder=3)
    if closed.closures:
        ax.legend(loc="upper right")
    return ax
