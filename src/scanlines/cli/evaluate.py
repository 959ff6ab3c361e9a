"""``scanlines eval``: benchmark method specs on simulated scans with exact truth, or
(``--real LOG``) their scan-to-scan repeatability on real logs, without labels."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from scanlines.cli.common import guarded

if TYPE_CHECKING:
    from scanlines.evaluation.evaluate import EvalResult
    from scanlines.evaluation.repeatability import RepeatabilityResult
    from scanlines.evaluation.scenes import SceneSet
    from scanlines.evaluation.scores import Tolerances

SPEC_HELP = (
    "Method spec METHOD[:PRESET][?NAME=VALUE&...][@LABEL], e.g. adaptive, adaptive:paper, "
    "'adaptive?k=4&fit=paper@k4'. Repeatable; default adaptive. 'truth' adds a reference row, "
    "not a method: the true segments fitted by total least squares to their own true returns, "
    "with the true breakpoints and corners; the best any segmentation can do with exact "
    "boundaries: the ceiling of the segment metrics."
)


def register(app: typer.Typer) -> None:
    app.command(
        "eval",
        help="Score methods (and the 'truth' ceiling row) on simulated scenes with exact ground "
        "truth: tables, CSV/JSON, plots. With --real LOG: the scan-to-scan repeatability of "
        "the methods on a real log, no labels needed.",
    )(guarded(eval_command))


def eval_command(
    method: Annotated[list[str] | None, typer.Option("--method", "-m", help=SPEC_HELP)] = None,
    sensor: Annotated[
        list[str] | None,
        typer.Option("--sensor", "-s", help="Sensor preset, repeatable; default all four."),
    ] = None,
    scenes_per_sensor: Annotated[
        int | None,
        typer.Option(
            "--scenes-per-sensor", "-n", help="Scenes per sensor (default 100; with --scenes: all)."
        ),
    ] = None,
    seed: Annotated[int | None, typer.Option(help="Base seed of the scenes (default 0).")] = None,
    scenes: Annotated[
        Path | None, typer.Option("--scenes", help="Evaluate on a saved scene set (.npz).")
    ] = None,
    save_scenes: Annotated[
        Path | None, typer.Option("--save-scenes", help="Also save the generated scenes (.npz).")
    ] = None,
    out: Annotated[Path, typer.Option(help="Folder for CSV, JSON and figures.")] = Path(
        "scanlines-eval"
    ),
    noise: Annotated[
        str | None, typer.Option(help="realistic (the preset's noise, default) or exact.")
    ] = None,
    tol_beams: Annotated[
        int, typer.Option("--tol-beams", help="Event match tolerance, beams.")
    ] = 2,
    tol_rho: Annotated[
        float, typer.Option("--tol-rho", help="Segment match |drho| tolerance, metres.")
    ] = 0.05,
    tol_alpha: Annotated[
        float, typer.Option("--tol-alpha", help="Segment match |dalpha| tolerance, degrees.")
    ] = 4.0,
    workers: Annotated[int, typer.Option(help="Processes.")] = 1,
    worst: Annotated[int, typer.Option(help="Scans in worst.png.")] = 4,
    plots: Annotated[bool, typer.Option(help="Write bars.png and worst.png.")] = True,
    real: Annotated[
        list[Path] | None,
        typer.Option(
            "--real",
            help="A real log (any format 'scanlines info' reads), repeatable: measure the "
            "scan-to-scan repeatability of the methods instead (label-free; pairs 1-3 records "
            "apart registered by ICP from the log's poses, or ICP alone). Writes "
            "repeatability.csv, repeatability_pairs.csv and repeatability.json into --out.",
        ),
    ] = None,
    scans: Annotated[
        int | None,
        typer.Option("--scans", min=2, help="With --real: the first N scans of each log."),
    ] = None,
) -> None:
    from scanlines.evaluation.specs import parse_specs

    specs = parse_specs(method or ["adaptive"])
    if real:
        _check_real_options(sensor, scenes_per_sensor, seed, scenes, save_scenes, noise, specs)
        results = [_repeatability_with_progress(log, specs, scans) for log in real]
        from scanlines.evaluation.repeatability import write_results

        for path in write_results(results, out):
            typer.echo(f"wrote {path}")
        return
    if scans is not None:
        from scanlines.errors import ParameterError

        raise ParameterError("--scans limits the scans of --real logs; give --real LOG")
    tol = _tolerances(tol_beams, tol_rho, tol_alpha)
    scene_set = _scene_set(scenes, save_scenes, sensor, scenes_per_sensor, seed, noise)
    result = _evaluate_with_progress(
        specs,
        sensor,
        scenes_per_sensor,
        0 if seed is None else seed,
        noise or "realistic",
        tol,
        scene_set,
        workers,
    )
    _print_tables(result)
    paths = _write_outputs(result, out, worst if plots else None)
    if save_scenes is not None:
        paths.append(save_scenes)
    for path in paths:
        typer.echo(f"wrote {path}")


def _tolerances(beams: int, rho: float, alpha_deg: float) -> Tolerances:
    import math

    from scanlines.errors import ParameterError
    from scanlines.evaluation.scores import Tolerances

    try:
        return Tolerances(event_beams=beams, rho=rho, alpha=math.radians(alpha_deg))
    except ValueError as error:
        raise ParameterError(f"bad tolerance: {error}") from None


def _scene_set(
    scenes: Path | None,
    save_scenes: Path | None,
    sensors: list[str] | None,
    n: int | None,
    seed: int | None,
    noise: str | None,
) -> SceneSet | None:
    """The scene set to evaluate on: loaded, generated and saved, or none (generate)."""
    from scanlines.errors import ParameterError
    from scanlines.evaluation.scenes import DEFAULT_SCENES, generate_scene_set, load_scene_set

    if scenes is not None:
        if save_scenes is not None:
            raise ParameterError("--scenes and --save-scenes exclude each other")
        if seed is not None or noise is not None:
            raise ParameterError("--seed and --noise describe generated scenes, not --scenes")
        return load_scene_set(scenes)
    if save_scenes is None:
        return None
    with _progress("generating scenes") as advance:
        generated = generate_scene_set(
            sensors,
            DEFAULT_SCENES if n is None else n,
            0 if seed is None else seed,
            noise or "realistic",
            on_scene=advance,
        )
    generated.save(save_scenes)
    return generated


def _evaluate_with_progress(specs, sensors, n, seed, noise, tol, scene_set, workers) -> EvalResult:
    from scanlines.evaluation.evaluate import evaluate

    with _progress("evaluating") as advance:
        return evaluate(
            specs,
            sensors,
            n,
            seed,
            tol=tol,
            noise=noise,
            scenes=scene_set,
            workers=workers,
            on_scene=advance,
        )


def _check_real_options(sensor, n, seed, scenes, save_scenes, noise, specs) -> None:
    """--real measures real logs: the options of simulated scenes, and 'truth', do not apply."""
    from scanlines.errors import ParameterError

    given = [
        name
        for name, value in (
            ("--sensor", sensor),
            ("--scenes-per-sensor", n),
            ("--seed", seed),
            ("--scenes", scenes),
            ("--save-scenes", save_scenes),
            ("--noise", noise),
        )
        if value is not None
    ]
    if given:
        raise ParameterError(f"{', '.join(given)}: options of simulated scenes, not of --real logs")
    if any(spec.is_truth for spec in specs):
        raise ParameterError("'truth' needs simulated scenes; real logs have no truth")


def _repeatability_with_progress(log: Path, specs, scans: int | None) -> RepeatabilityResult:
    from scanlines.evaluation.repeatability import repeatability

    with _progress(f"{log.name}: pairs, then scans per method", unit="steps") as advance:
        result = repeatability(log, specs, scans, on_progress=advance)
    _print_repeatability(result)
    return result


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


class _progress:
    """A transient rich progress bar (on stderr); gives ``advance(done, total)``."""

    def __init__(self, description: str, unit: str = "scenes") -> None:
        self.description = description
        self.unit = unit

    def __enter__(self):
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

        self.bar = Progress(
            "{task.description}",
            BarColumn(),
            MofNCompleteColumn(),
            self.unit,
            TimeElapsedColumn(),
            transient=True,
            console=Console(stderr=True),
        )
        self.bar.__enter__()
        self.task = self.bar.add_task(self.description, total=None)
        return self.advance

    def advance(self, done: int, total: int) -> None:
        self.bar.update(self.task, completed=done, total=total)

    def __exit__(self, *exc: object) -> None:
        self.bar.__exit__(*exc)


def _print_tables(result: EvalResult) -> None:
    from rich.box import SIMPLE_HEAD
    from rich.console import Console
    from rich.table import Table

    from scanlines.evaluation.evaluate import TABLE_COLUMNS, tolerance_caption

    config = result.config
    caption = (
        f"{tolerance_caption(config.tol)}. Rates pooled over scans; split/merge totals; "
        "accuracy: mean per-scan rate; us/scan: median extraction time."
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


TABLE_WIDTH = 180
"""Console width when the output is not a terminal (the tables are wide)."""


def _write_outputs(result: EvalResult, out: Path, worst: int | None) -> list[Path]:
    paths = [*result.to_csv(out), result.to_json(out / "summary.json")]
    if worst is not None:
        from scanlines.viz.evaluation import plot_bars, plot_worst
        from scanlines.viz.figures import save

        paths.append(save(plot_bars(result), out / "bars.png"))
        paths.append(save(plot_worst(result, worst), out / "worst.png"))
    return paths
