"""``python -m tools.reproduce``: redo the paper's experiments and write ``docs/RESULTS.md``."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer

from scanlines.cli.common import guarded, jobs_option


def register(app: typer.Typer) -> None:
    app.command(
        help=(
            "Redo the paper's experiments (Tables 1 and 3, Fig. 13, its similarity and speed "
            "claims) and every method on simulated ground truth, from the data shipped in the "
            "repository; writes OUT/RESULTS.md and OUT/figures/*.png."
        ),
    )(guarded(reproduce_command))


def reproduce_command(
    out: Annotated[
        Path, typer.Option("--out", "-o", help="Folder for RESULTS.md and figures/.")
    ] = Path("docs"),
    quick: Annotated[
        bool,
        typer.Option(
            "--quick",
            help="Small run (tests): 3 scenes, 2 labelled frames, 20 real scans, 1 repeat.",
        ),
    ] = False,
    scenes_per_sensor: Annotated[
        int | None,
        typer.Option(
            "--scenes-per-sensor",
            "-n",
            help="Simulated scenes per sensor preset for the ground-truth table "
            "(default 100; 3 with --quick).",
        ),
    ] = None,
    seed: Annotated[int, typer.Option(help="Base seed of the simulated scenes.")] = 0,
    jobs: Annotated[
        int | None,
        typer.Option(
            "--jobs", "-j", help="Processes scoring simulated scenes (default: every core)."
        ),
    ] = None,
) -> None:
    from scanlines.report import command_line
    from tools.reproduce import reproduce
    from tools.reproduce.experiments import ReproduceConfig

    config = ReproduceConfig.quick_config(seed=seed) if quick else ReproduceConfig(seed=seed)
    if scenes_per_sensor is not None:
        config = replace(config, scenes_per_sensor=scenes_per_sensor)
    config = replace(config, jobs=jobs_option(jobs))

    def stage(text: str) -> None:
        print(f"tools.reproduce: {text}", file=sys.stderr, flush=True)

    result, paths = reproduce(
        out, config, command=command_line(program="python -m tools.reproduce"), on_stage=stage
    )
    for h in result.headlines("adaptive"):
        g = h.similarity_gain_pct
        typer.echo(
            f"{h.dataset} ({h.n_scans} scans): similarity error adaptive "
            f"{h.similarity_mm:.2f} mm vs iepf {h.reference_similarity_mm:.2f} mm, "
            f"{abs(g):.1f} % {'lower' if g >= 0 else 'higher'} (paper: 8.3 % lower); time "
            f"{h.median_us:,.0f} vs {h.reference_median_us:,.0f} us/scan, "
            f"iepf time / adaptive time = {h.speed_ratio:.2f} (paper: 4)"
        )
    typer.echo(f"took {result.elapsed_s:.0f} s")
    for path in paths:
        typer.echo(f"wrote {path}")


def main() -> None:
    app = typer.Typer(add_completion=False, pretty_exceptions_enable=False)
    register(app)
    app(prog_name="python -m tools.reproduce")


if __name__ == "__main__":
    main()
