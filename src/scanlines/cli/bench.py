"""``scanlines bench``: time every method on real and simulated scans, in one process."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from scanlines.cli.common import guarded

if TYPE_CHECKING:
    from scanlines.bench.results import BenchResult
    from scanlines.report import TableData

TABLE_WIDTH = 160
"""Console width when the output is not a terminal."""


def register(app: typer.Typer) -> None:
    app.command(
        "bench",
        help=(
            "Time every method (median/p90 us per scan, scans/s, ratio to iepf) on the shipped "
            "real excerpts and simulated scans of each sensor preset; scaling over beam counts; "
            "Extractor.batch vs the loop; tables on stdout, --json for the numbers."
        ),
    )(guarded(bench_command))


def bench_command(
    method: Annotated[
        list[str] | None,
        typer.Option("--method", "-m", help="Method to time, repeatable; default all."),
    ] = None,
    sensor: Annotated[
        list[str] | None,
        typer.Option("--sensor", "-s", help="Sensor preset to simulate, repeatable; default all."),
    ] = None,
    quick: Annotated[
        bool,
        typer.Option(
            "--quick", help="Tiny run for CI: few scans, 1 repeat, beam counts 100 and 1000."
        ),
    ] = False,
    real_scans: Annotated[
        int | None, typer.Option("--real-scans", help="Scans per real excerpt (default 100).")
    ] = None,
    sim_scans: Annotated[
        int | None, typer.Option("--sim-scans", help="Simulated scans per preset (default 50).")
    ] = None,
    repeats: Annotated[
        int | None, typer.Option("--repeats", "-r", help="Timed passes (default 3).")
    ] = None,
    beams: Annotated[
        list[int] | None,
        typer.Option(
            "--beams",
            help="Beam count of the scaling run, repeatable (default 100 300 1000 3000 10000).",
        ),
    ] = None,
    scaling_scans: Annotated[
        int | None,
        typer.Option(
            "--scaling-scans", help="Scans per beam count in the scaling run (default 10)."
        ),
    ] = None,
    no_scaling: Annotated[bool, typer.Option("--no-scaling", help="Skip the scaling run.")] = False,
    no_batch: Annotated[
        bool, typer.Option("--no-batch", help="Skip Extractor.batch vs the loop.")
    ] = False,
    seed: Annotated[int, typer.Option(help="Base seed of the simulated scenes.")] = 0,
    jobs: Annotated[
        int,
        typer.Option(
            "--jobs", "-j", help="Most jobs in the run-by-jobs section (default 1: clean timings)."
        ),
    ] = 1,
    no_pipeline: Annotated[
        bool, typer.Option("--no-pipeline", help="Skip the run stages, jobs and cold start.")
    ] = False,
    cold_start: Annotated[
        bool | None,
        typer.Option(
            "--cold-start/--no-cold-start",
            help="Time the first results of a fresh process (default: on, off with --quick).",
        ),
    ] = None,
    profile: Annotated[
        bool,
        typer.Option("--profile", help="Profile adaptive over the intel excerpt."),
    ] = False,
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Also write the measurements as JSON.")
    ] = None,
) -> object:  # the BenchResult (typer evaluates the annotation at start-up)
    from scanlines.bench import measure
    from scanlines.cli.progress import progress
    from scanlines.report import command_line

    changes = {
        key: value
        for key, value in {
            "real_scans": real_scans,
            "sim_scans": sim_scans,
            "repeats": repeats,
            "scaling_scans": scaling_scans,
        }.items()
        if value is not None
    }
    changes.update(
        methods=tuple(method or ()),
        sensors=tuple(sensor or ()),
        seed=seed,
        batch=not no_batch,
        profile=profile,
        pipeline=not no_pipeline,
        jobs=jobs,
    )
    if cold_start is not None:
        changes["cold_start"] = cold_start
    if beams:
        changes["beam_counts"] = tuple(beams)
    if no_scaling:
        changes["beam_counts"] = ()
    make = measure.BenchConfig.quick_config if quick else measure.BenchConfig
    config = make(**changes)
    config = config.validated()  # bad input ends here, before anything is timed

    with progress("bench", unit="") as tick:
        result = measure.run(config, command=command_line(), progress=tick.stage)
    _print(result)
    if json_path is not None:
        typer.echo(f"wrote {result.to_json(json_path)}")
    return result  # for a caller that writes a page of it (the repository's tools)


def _print(result: BenchResult) -> None:
    from rich.console import Console

    console = Console()
    if not console.is_terminal:
        console = Console(width=TABLE_WIDTH)
    m = result.machine
    console.print(
        f"{m['cpu']}, {m['cores_logical']} cores, {m['python']}, numpy {m['numpy']}; "
        f"{len(result.methods)} methods, {result.elapsed_s:.0f} s. {result.reference_note}"
    )
    for table in result.tables():
        console.print(_rich(table))
    for table in result.profile_tables():
        console.print(_rich(table))


def _rich(data: TableData):
    from rich.box import SIMPLE_HEAD
    from rich.table import Table

    table = Table(
        title=data.title,
        caption=data.caption or None,
        caption_justify="left",
        box=SIMPLE_HEAD,
        title_justify="left",
    )
    for i, column in enumerate(data.columns):
        if i < data.left:
            table.add_column(column, style="bold" if i == 0 else None, no_wrap=True)
        else:
            table.add_column(column, justify="right", no_wrap=True)
    for row in data.rows:
        table.add_row(*row)
    return table
