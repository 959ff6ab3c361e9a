"""``scanlines eval sim``, ``eval family`` and ``eval labels``: methods scored on simulated
scenes with exact truth, or on hand-labelled real frames; ``register`` adds every mode."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from scanlines.cli.common import guarded, jobs_option
from scanlines.cli.eval_options import (
    ConfigsOption,
    EvalProfileOption,
    MethodsOption,
    OutOption,
    echo_written,
    method_specs,
)
from scanlines.cli.eval_reports import (
    TABLE_WIDTH,
    _print_family,
    _print_tables,
)
from scanlines.cli.progress import progress

if TYPE_CHECKING:
    from scanlines.evaluation.evaluate import EvalResult
    from scanlines.evaluation.scenes import SceneSet
    from scanlines.evaluation.scores import Tolerances


def register(app: typer.Typer) -> None:
    from scanlines.cli import eval_real, maps, trajectory
    from scanlines.cli.eval_legacy import EvalGroup

    group = typer.Typer(
        cls=EvalGroup,
        help="Score methods, maps and trajectories. `scanlines eval` alone is `eval sim`; "
        "the flag forms (`eval --real LOG`, `eval --map LOG`, ...) still run, as the "
        "subcommand they name.",
        no_args_is_help=False,
    )
    group.command(
        "sim",
        help="Score methods (and the 'truth' ceiling row) on simulated scenes of the sensor "
        "presets, with exact ground truth: tables, CSV/JSON, plots.",
    )(guarded(sim_command))
    group.command(
        "family",
        help="Score methods on the sensor family (drawn sensors and the 4 corner sensors of "
        "scanlines.sim.family), clutter scenes, the truth's don't-care events, the truth row "
        "added: every sensor's breakpoint F1, corner F1, TruePos / truth row, FalsePos - truth "
        "row, and the worst sensor per figure; writes family.csv and family_worst.csv.",
    )(guarded(family_command))
    group.command(
        "labels",
        help="Score methods on the hand-labelled frames of the shipped real logs (intel, "
        "freiburg, urg; default all). Writes labelled.csv into --out.",
    )(guarded(labels_command))
    eval_real.register(group)
    maps.register_eval(group)
    trajectory.register(group)
    app.add_typer(group, name="eval")


SensorsOption = Annotated[
    list[str] | None,
    typer.Option("--sensor", "-s", help="Sensor preset, repeatable; default all four."),
]
SeedOption = Annotated[int | None, typer.Option(help="Base seed of the scenes (default 0).")]
ScenesOption = Annotated[
    Path | None, typer.Option("--scenes", help="Evaluate on a saved scene set (.npz).")
]
SaveScenesOption = Annotated[
    Path | None, typer.Option("--save-scenes", help="Also save the generated scenes (.npz).")
]
NoiseOption = Annotated[
    str | None, typer.Option(help="realistic (the preset's noise, default) or exact.")
]
TolBeamsOption = Annotated[
    int | None,
    typer.Option("--tol-beams", help="Event match tolerance, beams.", show_default="2"),
]
TolRhoOption = Annotated[
    float | None,
    typer.Option("--tol-rho", help="Segment match |drho| tolerance, metres.", show_default="0.05"),
]
TolAlphaOption = Annotated[
    float | None,
    typer.Option(
        "--tol-alpha", help="Segment match |dalpha| tolerance, degrees.", show_default="4.0"
    ),
]
EvalJobsOption = Annotated[
    int | None,
    typer.Option("--jobs", "-j", help="Processes scoring scenes (default: every core)."),
]
WorstOption = Annotated[int, typer.Option(help="Scans in worst.png.")]
PlotsOption = Annotated[bool, typer.Option(help="Write bars.png and worst.png.")]


def _clutter_option(default: str) -> object:
    return typer.Option(
        "--clutter/--no-clutter",
        help="Clutter scenes (legs, people, glass, curved walls, long corridors); "
        f"default {default}.",
    )


def _dont_care_option(default: str) -> object:
    return typer.Option(
        "--truth-dont-care/--no-truth-dont-care",
        help="Events the truth marks don't care (junctions, depth steps and turns the "
        f"noise hides) do not count; default {default}.",
    )


def sim_command(
    method: MethodsOption = None,
    config: ConfigsOption = None,
    sensor: SensorsOption = None,
    scenes_per_sensor: Annotated[
        int | None,
        typer.Option(
            "--scenes-per-sensor", "-n", help="Scenes per sensor (default 100; with --scenes: all)."
        ),
    ] = None,
    seed: SeedOption = None,
    scenes: ScenesOption = None,
    save_scenes: SaveScenesOption = None,
    out: OutOption = Path("scanlines-eval"),
    noise: NoiseOption = None,
    tol_beams: TolBeamsOption = None,
    tol_rho: TolRhoOption = None,
    tol_alpha: TolAlphaOption = None,
    jobs: EvalJobsOption = None,
    worst: WorstOption = 4,
    plots: PlotsOption = True,
    clutter: Annotated[bool, _clutter_option("off")] = False,
    truth_dont_care: Annotated[bool, _dont_care_option("off")] = False,
) -> None:
    specs = method_specs(method, config)
    tol = _tolerances(tol_beams, tol_rho, tol_alpha, truth_dont_care)
    scene_set = _scene_set(scenes, save_scenes, sensor, scenes_per_sensor, seed, noise, clutter)
    result = _evaluate_with_progress(
        specs, sensor, scenes_per_sensor, 0 if seed is None else seed, noise or "realistic",
        tol, scene_set, jobs_option(jobs), clutter,
    )  # fmt: skip
    _print_tables(result)
    paths = _write_outputs(result, out, worst if plots else None)
    echo_written([*paths, *([] if save_scenes is None else [save_scenes])])


def family_command(
    method: MethodsOption = None,
    config: ConfigsOption = None,
    scenes_per_sensor: Annotated[
        int | None,
        typer.Option("--scenes-per-sensor", "-n", help="Scenes per sensor (default 300)."),
    ] = None,
    seed: SeedOption = None,
    family_count: Annotated[
        int, typer.Option("--family-count", help="Drawn sensors (and the 4 corner sensors).")
    ] = 24,
    family_seed: Annotated[
        int, typer.Option("--family-seed", help="Seed of the drawn sensors.")
    ] = 0,
    save_scenes: SaveScenesOption = None,
    out: OutOption = Path("scanlines-eval"),
    noise: NoiseOption = None,
    tol_beams: TolBeamsOption = None,
    tol_rho: TolRhoOption = None,
    tol_alpha: TolAlphaOption = None,
    jobs: EvalJobsOption = None,
    worst: WorstOption = 4,
    plots: PlotsOption = True,
    clutter: Annotated[bool, _clutter_option("on")] = True,
    truth_dont_care: Annotated[bool, _dont_care_option("on")] = True,
) -> None:
    from scanlines.evaluation.family import DEFAULT_FAMILY_SCENES
    from scanlines.evaluation.specs import TRUTH, parse_specs

    specs = method_specs(method, config)
    if not any(s.is_truth for s in specs):
        specs = (*specs, *parse_specs([TRUTH]))
    sensors = list(_family_names(family_count, family_seed))
    n = DEFAULT_FAMILY_SCENES if scenes_per_sensor is None else scenes_per_sensor
    tol = _tolerances(tol_beams, tol_rho, tol_alpha, truth_dont_care)
    scene_set = _scene_set(None, save_scenes, sensors, n, seed, noise, clutter)
    result = _evaluate_with_progress(
        specs, sensors, n, 0 if seed is None else seed, noise or "realistic", tol, scene_set,
        jobs_option(jobs), clutter,
    )  # fmt: skip
    paths = [*_print_family(result, out), *_write_outputs(result, out, worst if plots else None)]
    echo_written([*paths, *([] if save_scenes is None else [save_scenes])])


def labels_command(
    samples: Annotated[
        list[str] | None,
        typer.Argument(
            metavar="[SAMPLE]...",
            help="Shipped logs with hand labels: intel, freiburg, urg or all.",
        ),
    ] = None,
    method: MethodsOption = None,
    config: ConfigsOption = None,
    tol_beams: TolBeamsOption = None,
    sensor_profile: EvalProfileOption = None,
    out: OutOption = Path("scanlines-eval"),
) -> None:
    from scanlines.sensor.profile import read_profile

    specs = method_specs(method, config)
    if any(spec.is_truth for spec in specs):
        from scanlines.errors import ParameterError

        raise ParameterError("'truth' needs simulated scenes; real logs have no truth")
    beams = _tolerances(tol_beams, None, None, truth_dont_care=False).event_beams
    profile = None if sensor_profile is None else read_profile(sensor_profile)
    _labelled(samples or ["all"], specs, beams, profile, out)


def _family_names(count: int, seed: int) -> tuple[str, ...]:
    from scanlines.errors import ParameterError
    from scanlines.sim.family import family_names

    try:
        return family_names(count, seed)
    except ValueError as error:
        raise ParameterError(f"--family-count/--family-seed: {error}") from None


def _tolerances(
    beams: int | None, rho: float | None, alpha_deg: float | None, truth_dont_care: bool
) -> Tolerances:
    import math

    from scanlines.errors import ParameterError
    from scanlines.evaluation.scores import Tolerances

    default = Tolerances()
    try:
        return Tolerances(
            event_beams=default.event_beams if beams is None else beams,
            rho=default.rho if rho is None else rho,
            alpha=default.alpha if alpha_deg is None else math.radians(alpha_deg),
            truth_dont_care=truth_dont_care,
        )
    except ValueError as error:
        raise ParameterError(f"bad tolerance: {error}") from None


def _scene_set(
    scenes: Path | None,
    save_scenes: Path | None,
    sensors: list[str] | None,
    n: int | None,
    seed: int | None,
    noise: str | None,
    clutter: bool = False,
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
    with progress("generating scenes", unit="scenes") as tick:
        generated = generate_scene_set(
            sensors,
            DEFAULT_SCENES if n is None else n,
            0 if seed is None else seed,
            noise or "realistic",
            clutter=clutter,
            on_scene=tick.update,
        )
    generated.save(save_scenes)
    return generated


def _evaluate_with_progress(
    specs, sensors, n, seed, noise, tol, scene_set, workers, clutter=False
) -> EvalResult:
    from scanlines.evaluation.evaluate import evaluate

    with progress("evaluating", unit="scenes") as tick:
        return evaluate(
            specs,
            sensors,
            n,
            seed,
            tol=tol,
            noise=noise,
            scenes=scene_set,
            workers=workers,
            on_scene=tick.update,
            clutter=clutter,
        )


def _labelled(names: list[str], specs, tolerance: int, profile, out: Path) -> None:
    from rich.box import SIMPLE_HEAD
    from rich.console import Console
    from rich.table import Table

    from scanlines.data.labels import LABEL_FILES
    from scanlines.errors import ParameterError
    from scanlines.evaluation.labelled import evaluate_labelled

    samples = list(LABEL_FILES) if "all" in names else names
    unknown = sorted(set(samples) - set(LABEL_FILES))
    if unknown:
        raise ParameterError(
            f"eval labels: no hand labels for {', '.join(unknown)}; "
            f"choose from {', '.join(LABEL_FILES)} or all"
        )
    with progress("scoring hand-labelled frames", unit="methods x logs") as tick:
        result = evaluate_labelled(
            specs, samples, tolerance=tolerance, sensor_profile=profile, on_progress=tick.update
        )
    rows = result.rows()
    table = Table(
        title="hand-labelled frames of the shipped real logs",
        caption=f"events matched within +-{tolerance} beams, uncertain labels don't care; "
        "segments, length, <5 returns and coverage over every scan of the excerpt",
        caption_justify="left",
        box=SIMPLE_HEAD,
    )
    for header in rows[0]:
        table.add_column(header.replace("_", " "), justify="right", no_wrap=True)
    for row in rows:
        table.add_row(*(f"{v:.3f}" if isinstance(v, float) else str(v) for v in row.values()))
    console = Console()
    if not console.is_terminal:
        console = Console(width=TABLE_WIDTH)
    console.print(table)
    out.mkdir(parents=True, exist_ok=True)
    typer.echo(f"wrote {result.to_csv(out / 'labelled.csv')}")


def _write_outputs(result: EvalResult, out: Path, worst: int | None) -> list[Path]:
    paths = [*result.to_csv(out), result.to_json(out / "summary.json")]
    if worst is not None:
        from scanlines.viz.evaluation import plot_bars, plot_worst
        from scanlines.viz.figures import save

        paths.append(save(plot_bars(result), out / "bars.png"))
        paths.append(save(plot_worst(result, worst), out / "worst.png"))
    return paths
