"""What ``scanlines eval`` prints: the score tables, the family tables, the repeatability
table."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from scanlines.evaluation.evaluate import EvalResult
    from scanlines.evaluation.repeatability import RepeatabilityResult


def _print_repeatability(result: RepeatabilityResult) -> None:
    from rich.box import SIMPLE_HEAD
    from rich.console import Console
    from rich.table import Table

    from scanlines.evaluation.repeatability import TABLE_CAPTION, TABLE_COLUMNS

    console = Console()
    if not console.is_terminal:
        console = Console(width=TABLE_WIDTH)
    caption = f"{result.tol.caption()}.\n{TABLE_CAPTION}"
    table = Table(title=result.title(), caption=caption, caption_justify="left", box=SIMPLE_HEAD)
    table.add_column("method", style="bold", no_wrap=True)
    for header, _, _ in TABLE_COLUMNS:
        table.add_column(header.replace(" ", "\n", 1), justify="right", no_wrap=True)
    for row in result.table():
        table.add_row(*row)
    console.print(table)


def _print_tables(result: EvalResult) -> None:
    from rich.box import SIMPLE_HEAD
    from rich.console import Console
    from rich.table import Table

    from scanlines.evaluation.eval_results import COUNT_RATE_CAPTION
    from scanlines.evaluation.evaluate import TABLE_COLUMNS, tolerance_caption

    config = result.config
    caption = (
        f"{tolerance_caption(config.tol)}. Rates pooled over scans; split/merge totals; "
        f"us/scan: median extraction time; {COUNT_RATE_CAPTION}."
    )
    console = Console()
    if not console.is_terminal:
        console = Console(width=TABLE_WIDTH)
    for sensor in dict.fromkeys(r.sensor for r in result.summaries):
        first = next(r for r in result.summaries if r.sensor == sensor)
        title = (
            f"{sensor}: {first.summary.n_scans} scans, noise {config.noise}, seed {config.seed}"
            + (f", {config.source}" if config.source != "generated" else "")
        )
        table = Table(title=title, caption=caption, caption_justify="left", box=SIMPLE_HEAD)
        table.add_column("method", style="bold", no_wrap=True)
        for header, _, _ in TABLE_COLUMNS:
            table.add_column(header.replace(" ", "\n", 1), justify="right", no_wrap=True)
        for row in result.table(sensor):
            table.add_row(*row)
        console.print(table)


def _print_family(result: EvalResult, out: Path) -> list[Path]:
    """The family tables: sensors, every figure per sensor and spec, the worst sensors.

    Returns the CSV files written (``family.csv``, ``family_worst.csv``,
    ``family_sensors.csv``).
    """
    import math

    from rich.box import SIMPLE_HEAD
    from rich.console import Console
    from rich.table import Table

    from scanlines.evaluation.evaluate import tolerance_caption
    from scanlines.evaluation.family import FIGURES, family_rows, worst_rows
    from scanlines.report import number, write_csv
    from scanlines.sim import get_sensor

    console = Console()
    if not console.is_terminal:
        console = Console(width=TABLE_WIDTH)
    config = result.config
    sensors = []
    for name in config.sensors:
        spec = get_sensor(name)
        n = spec.noise
        sensors.append(
            {
                "sensor": name,
                "beams": spec.n_beams,
                "step_deg": math.degrees(abs(spec.angle_increment)),
                "fov_deg": 360.0
                if spec.full_circle
                else math.degrees(abs(spec.angle_increment) * (spec.n_beams - 1)),
                "sigma_cm": 100 * n.sigma,
                "sigma_slope_pct": 100 * n.sigma_slope,
                "bias_cm": 100 * n.bias,
                "bias_rel_pct": 100 * n.bias_rel,
                "range_max_m": spec.range_max,
                "dropout_pct": 100 * n.dropout_prob,
                "outlier_pct": 100 * n.outlier_prob,
                "mixed_pct": 100 * n.mixed_pixel_prob,
            }
        )
    table = Table(title="family sensors", box=SIMPLE_HEAD)
    for key in sensors[0]:
        table.add_column(key, justify="right" if key != "sensor" else "left")
    for row in sensors:
        table.add_row(
            *(
                v if isinstance(v, str) else number(v, "d" if isinstance(v, int) else ".2f")
                for v in row.values()
            )
        )
    console.print(table)

    rows = family_rows(result)
    labels = list(dict.fromkeys(r.label for r in rows))
    for name, title, _, target in FIGURES:
        table = Table(
            title=f"{title} per sensor (target on the worst sensor: "
            f"{'>=' if name != 'false_pos_excess' else '<='} {target:g})",
            box=SIMPLE_HEAD,
        )
        table.add_column("sensor", no_wrap=True)
        for label in labels:
            table.add_column(label, justify="right", no_wrap=True)
        for sensor in config.sensors:
            values = {r.label: getattr(r, name) for r in rows if r.sensor == sensor}
            table.add_row(sensor, *(number(values[label], ".3f") for label in labels))
        console.print(table)
    worst = worst_rows(rows)
    caption = (
        f"{len(config.sensors)} sensors x {config.n} scenes, seed {config.seed}, "
        f"{'clutter' if config.clutter else 'default'} scenes; {tolerance_caption(config.tol)}"
    )
    table = Table(
        title="worst sensor per figure", caption=caption, caption_justify="left", box=SIMPLE_HEAD
    )
    table.add_column("method", no_wrap=True)
    for _, title, end, target in FIGURES:
        table.add_column(f"{title}\n({'>=' if end == 'min' else '<='} {target:g})", justify="right")
    for label in labels:
        mine = {w.figure: w for w in worst if w.label == label}
        table.add_row(
            label,
            *(
                f"{number(mine[f].value, '.3f')} {'ok' if mine[f].met else 'NO'} {mine[f].sensor}"
                if f in mine
                else "-"
                for f, _, _, _ in FIGURES
            ),
        )
    console.print(table)
    out.mkdir(parents=True, exist_ok=True)
    return [
        write_csv(out / "family_sensors.csv", sensors),
        write_csv(out / "family.csv", [r.to_dict() for r in rows]),
        write_csv(out / "family_worst.csv", [w.to_dict() for w in worst]),
    ]


TABLE_WIDTH = 180
"""Console width when the output is not a terminal (the tables are wide)."""
