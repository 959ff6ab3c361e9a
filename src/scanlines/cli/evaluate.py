"""``scanlines eval``: benchmark method specs on simulated scans with exact truth, or
(``--real LOG``) their scan-to-scan repeatability on real logs, without labels."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from scanlines.cli.common import guarded, jobs_option
from scanlines.cli.eval_real import BareOption, PairsOption, RealOption
from scanlines.cli.eval_reports import (
    TABLE_WIDTH,
    _print_family,
    _print_tables,
    _progress,
)
from scanlines.cli.maps import AlignOption, LoopsOption, MapLogOption, MapPosesOption
from scanlines.cli.trajectory import ReferenceOption, TrajectoryOption

if TYPE_CHECKING:
    from scanlines.evaluation.evaluate import EvalResult
    from scanlines.evaluation.scenes import SceneSet
    from scanlines.evaluation.scores import Tolerances

SPEC_HELP = (
    "Method spec METHOD[:PRESET][?NAME=VALUE&...][@LABEL], e.g. adaptive, adaptive:paper, "
    "'adaptive?k=4&fit=paper@k4'. Repeatable; default adaptive. 'truth' adds a reference row, "
    "not a method: the true segments fitted by total least squares to their own true returns, "
    "with the true breakpoints and corners; the best any segmentation can do with exact "
    "boundaries: the ceiling of the segment metrics."
)
CONFIG_HELP = (
    "Extraction configuration (a TOML file of method, preset and a params table, as "
    "`scanlines run --config` takes): one more method row, labelled by the file name. "
    "Repeatable. Without --method, "
    "the configurations are the methods of the run (no default adaptive row)."
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
    config: Annotated[
        list[Path] | None, typer.Option("--config", metavar="FILE", help=CONFIG_HELP)
    ] = None,
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
        int | None,
        typer.Option("--tol-beams", help="Event match tolerance, beams.", show_default="2"),
    ] = None,
    tol_rho: Annotated[
        float | None,
        typer.Option(
            "--tol-rho", help="Segment match |drho| tolerance, metres.", show_default="0.05"
        ),
    ] = None,
    tol_alpha: Annotated[
        float | None,
        typer.Option(
            "--tol-alpha", help="Segment match |dalpha| tolerance, degrees.", show_default="4.0"
        ),
    ] = None,
    jobs: Annotated[
        int | None,
        typer.Option("--jobs", "-j", help="Processes scoring scenes (default: every core)."),
    ] = None,
    worst: Annotated[int, typer.Option(help="Scans in worst.png.")] = 4,
    plots: Annotated[bool, typer.Option(help="Write bars.png and worst.png.")] = True,
    real: RealOption = None,
    scans: Annotated[
        int | None,
        typer.Option("--scans", min=2, help="With --real: the first N scans of each log."),
    ] = None,
    pairs: PairsOption = None,
    bare: BareOption = False,
    family: Annotated[
        bool,
        typer.Option(
            "--family",
            help="Evaluate on the sensor family instead of the presets: --family-count drawn "
            "sensors and the 4 corner sensors (scanlines.sim.family), clutter scenes, the "
            "truth's don't-care events, the truth row added; -n defaults to 300. Prints every "
            "sensor's breakpoint F1, corner F1, TruePos / truth row, FalsePos - truth row, and "
            "the worst sensor per figure; writes family.csv and family_worst.csv.",
        ),
    ] = False,
    family_count: Annotated[
        int, typer.Option("--family-count", help="With --family: drawn sensors (default 24).")
    ] = 24,
    family_seed: Annotated[
        int, typer.Option("--family-seed", help="With --family: seed of the drawn sensors.")
    ] = 0,
    clutter: Annotated[
        bool | None,
        typer.Option(
            "--clutter/--no-clutter",
            help="Clutter scenes (legs, people, glass, curved walls, long corridors); "
            "default: on with --family, off otherwise.",
        ),
    ] = None,
    truth_dont_care: Annotated[
        bool | None,
        typer.Option(
            "--truth-dont-care/--no-truth-dont-care",
            help="Events the truth marks don't care (junctions, depth steps and turns the "
            "noise hides) do not count; default: on with --family, off otherwise.",
        ),
    ] = None,
    labels: Annotated[
        list[str] | None,
        typer.Option(
            "--labels",
            help="Score on the hand-labelled frames of a shipped real log instead: intel, "
            "freiburg, urg or all (repeatable). Writes labelled.csv into --out.",
        ),
    ] = None,
    sensor_profile: Annotated[
        Path | None,
        typer.Option(
            "--sensor-profile",
            help="Sensor profile (`scanlines calibrate`) for every extraction; default: with "
            "--real and --labels, measured from the log; on simulated scenes, each scan's own.",
        ),
    ] = None,
    map_log: MapLogOption = None,
    poses: MapPosesOption = None,
    align: AlignOption = False,
    loops: LoopsOption = True,
    trajectory: TrajectoryOption = None,
    reference: ReferenceOption = None,
) -> None:
    from scanlines.cli.eval_real import check_bare, repeatability_with_progress
    from scanlines.errors import ParameterError
    from scanlines.evaluation.specs import TRUTH, parse_specs

    if trajectory is not None or reference is not None:
        from scanlines.cli.trajectory import evaluate_trajectory_command

        others = map_log or real or labels or family or scenes is not None or method or config
        return evaluate_trajectory_command(trajectory, reference, out, bool(others))
    from scanlines.sensor.profile import read_profile

    configured = _config_specs(config or [])
    specs = parse_specs([*configured, *(method or ([] if configured else ["adaptive"]))])
    if map_log is not None:
        if real or labels or family or scenes is not None or (method and len(method) > 1):
            raise ParameterError(
                "--map scores one method on one log; it excludes --real, "
                "--labels, --family, --scenes and a second --method"
            )
        from scanlines.cli.maps import evaluate_map_command

        evaluate_map_command(
            map_log, specs[0], scans, sensor_profile, poses, out, align, loops=loops
        )
        return
    if poses is not None or align:
        raise ParameterError("--poses and --align go with a --map LOG")
    check_bare(bare, real, sensor_profile)
    profile = None if sensor_profile is None else read_profile(sensor_profile)
    if labels:
        _check_real_options(sensor, scenes_per_sensor, seed, scenes, save_scenes, noise, specs)
        _refuse_tolerances("--labels", tol_rho=tol_rho, tol_alpha=tol_alpha)
        beams = _tolerances(tol_beams, None, None, truth_dont_care=False).event_beams
        _labelled(labels, specs, beams, profile, out)
        return
    if real:
        _check_real_options(sensor, scenes_per_sensor, seed, scenes, save_scenes, noise, specs)
        _refuse_tolerances("--real", tol_beams=tol_beams, tol_rho=tol_rho, tol_alpha=tol_alpha)
        results = [
            repeatability_with_progress(log, specs, scans, profile, pairs, bare) for log in real
        ]
        from scanlines.evaluation.repeatability import write_results

        for path in write_results(results, out):
            typer.echo(f"wrote {path}")
        return
    if scans is not None:
        from scanlines.errors import ParameterError

        raise ParameterError("--scans limits the scans of --real logs; give --real LOG")
    if family:
        if sensor:
            raise ParameterError("--family and --sensor exclude each other")
        if scenes is not None:
            raise ParameterError("--family generates its scenes; it excludes --scenes")
        sensor = list(_family_names(family_count, family_seed))
        if scenes_per_sensor is None:
            from scanlines.evaluation.family import DEFAULT_FAMILY_SCENES

            scenes_per_sensor = DEFAULT_FAMILY_SCENES
        if not any(s.is_truth for s in specs):
            specs = (*specs, *parse_specs([TRUTH]))
    use_clutter = family if clutter is None else clutter
    tol = _tolerances(
        tol_beams, tol_rho, tol_alpha, family if truth_dont_care is None else truth_dont_care
    )
    scene_set = _scene_set(scenes, save_scenes, sensor, scenes_per_sensor, seed, noise, use_clutter)
    result = _evaluate_with_progress(
        specs,
        sensor,
        scenes_per_sensor,
        0 if seed is None else seed,
        noise or "realistic",
        tol,
        scene_set,
        jobs_option(jobs),
        use_clutter,
    )
    paths: list[Path] = []
    if family:
        paths += _print_family(result, out)
    else:
        _print_tables(result)
    paths += _write_outputs(result, out, worst if plots else None)
    if save_scenes is not None:
        paths.append(save_scenes)
    for path in paths:
        typer.echo(f"wrote {path}")


def _config_specs(paths: list[Path]) -> list:
    """One method spec per ``--config`` file: its method, preset and parameters (spelled
    as a spec writes them), labelled by the file name."""
    from scanlines.config import load_config
    from scanlines.evaluation.specs import MethodSpec

    specs = []
    for path in paths:
        loaded = load_config(path)
        params = tuple(loaded.cli_values().items())
        specs.append(MethodSpec(loaded.method, loaded.preset, params, label=path.name))
    return specs


def _family_names(count: int, seed: int) -> tuple[str, ...]:
    from scanlines.errors import ParameterError
    from scanlines.sim.family import family_names

    try:
        return family_names(count, seed)
    except ValueError as error:
        raise ParameterError(f"--family-count/--family-seed: {error}") from None


def _refuse_tolerances(mode: str, **given: float | None) -> None:
    """Tolerances that ``mode`` does not match with are an error, not ignored."""
    from scanlines.errors import ParameterError

    named = [f"--{name.replace('_', '-')}" for name, value in given.items() if value is not None]
    if named:
        why = (
            "--labels scores events only (--tol-beams)"
            if mode == "--labels"
            else "--real measures repeatability, with its own tolerances"
        )
        raise ParameterError(f"{', '.join(named)} do not apply: {why}")


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
    with _progress("generating scenes") as advance:
        generated = generate_scene_set(
            sensors,
            DEFAULT_SCENES if n is None else n,
            0 if seed is None else seed,
            noise or "realistic",
            clutter=clutter,
            on_scene=advance,
        )
    generated.save(save_scenes)
    return generated


def _evaluate_with_progress(
    specs, sensors, n, seed, noise, tol, scene_set, workers, clutter=False
) -> EvalResult:
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
            clutter=clutter,
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
            f"--labels: no hand labels for {', '.join(unknown)}; "
            f"choose from {', '.join(LABEL_FILES)} or all"
        )
    result = evaluate_labelled(specs, samples, tolerance=tolerance, sensor_profile=profile)
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
