"""Commands on whole logs: ``info``, ``run``, ``plot`` and ``demo``."""

from __future__ import annotations

import gc
from pathlib import Path
from typing import Annotated, Literal

import typer

from scanlines.cli.common import (
    NPZ_HELP,
    AngleMinOption,
    AngleStepOption,
    ConfigMethodOption,
    ConfigOption,
    ConventionOption,
    FovOption,
    JobsOption,
    LogArgument,
    MaxBeamsOption,
    OnErrorOption,
    OverwriteOption,
    ParamOption,
    PresetOption,
    ProfileOption,
    RangeMaxOption,
    ScansOption,
    TopicOption,
    guarded,
    jobs_option,
    method_options,
    profile_for_run,
    reader_options,
    with_mounting,
    writable,
)
from scanlines.cli.log_reports import (
    _bins_text,
    _print_description,
    _print_summary,
    _run_with_progress,
)
from scanlines.reader_options import SCANS_HELP


def register(app: typer.Typer) -> None:
    app.command("info", help="Describe a log: format, scans, beams, ranges, time span.")(
        guarded(info_command)
    )
    app.command("run", help="Extract features from every scan of a log.")(guarded(run_command))
    app.command(
        "calibrate",
        help="Measure a sensor profile (noise against range, dropouts, outliers) from a log.",
    )(guarded(calibrate_command))
    app.command("plot", help="Draw one scan, or a grid of scans, with their features.")(
        guarded(plot_command)
    )
    app.command("demo", help="Run the default method on the shipped Intel excerpt.")(
        guarded(demo_command)
    )
    app.command(
        "sample",
        help="The path of a shipped sample log (intel, freiburg, urg), for any command: "
        "LOG=$(scanlines sample intel). Without a name, every sample and its path.",
    )(guarded(sample_command))


def info_command(
    log: LogArgument,
    fov: FovOption = None,
    angle_convention: ConventionOption = None,
    topic: TopicOption = None,
    angle_min: AngleMinOption = None,
    angle_increment: AngleStepOption = None,
    on_error: OnErrorOption = "fail",
    max_beams: MaxBeamsOption = None,
    range_max: RangeMaxOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    import json

    from scanlines.io import open_log
    from scanlines.runs.runner import describe_log

    options = reader_options(
        fov, angle_convention, topic, angle_min, angle_increment, on_error, max_beams, range_max
    )
    with open_log(log, options=options) as reader:
        description = describe_log(reader)
    if as_json:
        typer.echo(json.dumps(description.to_dict(), indent=2, default=str))
        return
    _print_description(description)


def run_command(
    logs: Annotated[
        list[Path],
        typer.Argument(
            help="Logs (CARMEN, ROS bag, .dat, .csv, .npz), folders of logs, or globs. " + NPZ_HELP,
            metavar="LOG...",
        ),
    ],
    method: ConfigMethodOption = None,
    preset: PresetOption = None,
    param: ParamOption = None,
    config: ConfigOption = None,
    scans: ScansOption = None,
    out: Annotated[
        Path | None,
        typer.Option(help="Output: .jsonl, .csv, .mcap, .rrd (Rerun), or a ROS 2 bag directory."),
    ] = None,
    overwrite: OverwriteOption = False,
    frame: Annotated[
        Literal["sensor", "world"],
        typer.Option(help="Features in the sensor frame, or the world frame (needs poses)."),
    ] = "sensor",
    on_error: OnErrorOption = "fail",
    max_beams: MaxBeamsOption = None,
    range_max: RangeMaxOption = None,
    fov: FovOption = None,
    angle_convention: ConventionOption = None,
    topic: TopicOption = None,
    angle_min: AngleMinOption = None,
    angle_increment: AngleStepOption = None,
    sensor_profile: ProfileOption = None,
    jobs: JobsOption = None,
    output_format: Annotated[
        Literal["jsonl", "csv", "mcap", "rrd", "parquet"] | None,
        typer.Option(
            "--format",
            help="Output format for several logs or a dataset (parquet: one dataset "
            "for all logs; default: by --out's suffix, else jsonl).",
        ),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(
            help="Run on Dask: a scheduler address, or 'local' for a LocalCluster of "
            "--jobs workers (several logs or parquet only).",
        ),
    ] = None,
    chunk_records: Annotated[
        int,
        typer.Option(
            help="Several logs: a longer log is split in tasks of this many scans.", min=1
        ),
    ] = 5000,
) -> None:
    from scanlines.errors import ParameterError
    from scanlines.extractor import Extractor
    from scanlines.io import open_log
    from scanlines.runs.runner import parse_slice

    method, preset, params = method_options(method, preset, param, config)
    if _many(logs, out, output_format):
        from scanlines.cli.fleet import run_many

        options = reader_options(
            fov,
            angle_convention,
            topic,
            angle_min,
            angle_increment,
            on_error,
            max_beams,
            range_max,
        )
        run_many(logs, out, output_format, method=method, preset=preset,
                 params=params, options=options, sensor_profile=sensor_profile,
                 jobs=jobs_option(jobs), scheduler=scheduler, chunk_records=chunk_records,
                 overwrite=overwrite, scans=scans, frame=frame)  # fmt: skip
        return
    if scheduler is not None:
        raise ParameterError("--scheduler runs several logs or a parquet dataset")
    (log,) = logs
    if frame not in ("sensor", "world"):
        raise ParameterError(f"--frame must be sensor or world, got {frame!r}")
    if on_error not in ("fail", "skip"):
        raise ParameterError(f"--on-error must be fail or skip, got {on_error!r}")
    Extractor(method, preset, **params)  # bad parameters fail before the log is read
    selection = parse_slice(scans)
    if out is not None:
        from scanlines.io import writer_class

        writer_class(out)  # an unknown output suffix before the log is read
    writable(out, overwrite, with_meta=True)  # and a taken output before any work
    if out is not None and out.suffix.lower() == ".rrd":
        from scanlines.io.rerun_writer import require_rerun

        require_rerun()  # and a missing Rerun SDK
    options = reader_options(
        fov, angle_convention, topic, angle_min, angle_increment, on_error, max_beams, range_max
    )
    jobs = jobs_option(jobs)
    profile = profile_for_run(log, options, selection, sensor_profile)
    if frame == "world":
        options = with_mounting(log, options, profile)
    extractor = Extractor(method, preset, sensor_profile=profile, **params)
    # What is loaded now lives for the whole run: frozen, the collector no longer walks
    # it each time the chunks' records set off a collection.
    gc.freeze()
    with open_log(log, options=options) as reader:
        summary = _run_with_progress(reader, extractor, selection, out, frame, log, jobs, overwrite)
        notes = reader.notes
    _print_summary(summary, out, notes)
    if out is None:
        typer.echo(
            "scanlines: no --out given: the features were extracted and summarised, not written",
            err=True,
        )


def calibrate_command(
    log: LogArgument,
    out: Annotated[
        Path | None,
        typer.Option(
            help="Profile file (.json); default: <log name>.profile.json in the current folder."
        ),
    ] = None,
    plot: Annotated[
        Path | None, typer.Option(help="Figure of the noise curve (PNG, PDF, SVG).")
    ] = None,
    overwrite: OverwriteOption = False,
    scans: ScansOption = None,
    max_scans: Annotated[int, typer.Option(help="Scans measured (the first selected).")] = 500,
    fov: FovOption = None,
    angle_convention: ConventionOption = None,
    topic: TopicOption = None,
    angle_min: AngleMinOption = None,
    angle_increment: AngleStepOption = None,
    range_max: RangeMaxOption = None,
) -> None:
    from rich.console import Console
    from rich.table import Table

    from scanlines.errors import ParameterError
    from scanlines.io import open_log
    from scanlines.runs.runner import measure_profile, parse_slice
    from scanlines.sensor.profile import describe

    if max_scans < 1:
        raise ParameterError(f"--max-scans must be at least 1, got {max_scans}")
    options = reader_options(
        fov, angle_convention, topic, angle_min, angle_increment, range_max=range_max
    )
    with open_log(log, options=options) as reader:  # a missing log before its profile's folder
        out = out or Path(log.name.split(".")[0] + ".profile.json")  # never beside the log
        writable(out, overwrite)
        writable(plot, overwrite)
        profile = measure_profile(reader, parse_slice(scans), max_scans=max_scans, source=log.name)
    profile.save(out)
    table = Table(title=f"sensor profile of {log.name}", show_header=False)
    for what, value in describe(profile):
        table.add_row(what, value)
    table.add_row("noise bins", _bins_text(profile))
    Console().print(table)
    typer.echo(f"wrote {out}")
    if plot is not None:
        from scanlines.viz.figures import save
        from scanlines.viz.profile import plot_noise_curve

        save(plot_noise_curve(profile), plot)
        typer.echo(f"wrote {plot}")


def _many(logs: list[Path], out: Path | None, output_format: str | None) -> bool:
    """Several logs (or a folder of logs, or a glob), or a Parquet dataset: the fleet path.
    One folder that is a ROS 2 bag (``metadata.yaml``, or one storage file) is one log."""
    from scanlines.io.rosbag_files import is_ros2_bag_dir

    if len(logs) != 1 or output_format == "parquet":
        return True
    (log,) = logs
    if any(c in str(log) for c in "*?[") or (log.is_dir() and not is_ros2_bag_dir(log)):
        return True
    return out is not None and out.suffix.lower() == ".parquet"


def plot_command(
    log: LogArgument,
    scan: Annotated[int | None, typer.Option("--scan", help="Index of one scan to draw.")] = None,
    scans: Annotated[
        str | None, typer.Option("--scans", help=f"Scans for grids of 12. {SCANS_HELP}")
    ] = None,
    output: Annotated[
        Path,
        typer.Option("-o", "--output", help="Figure file; pages of a long selection: NAME-2...."),
    ] = Path("scanlines-plot.png"),
    max_pages: Annotated[
        int, typer.Option("--max-pages", help="Most pages (grids of 12 scans) drawn.", min=1)
    ] = 10,
    overwrite: OverwriteOption = False,
    method: ConfigMethodOption = None,
    preset: PresetOption = None,
    param: ParamOption = None,
    config: ConfigOption = None,
    fov: FovOption = None,
    angle_convention: ConventionOption = None,
    topic: TopicOption = None,
    angle_min: AngleMinOption = None,
    angle_increment: AngleStepOption = None,
    range_max: RangeMaxOption = None,
) -> None:
    from scanlines.errors import ParameterError
    from scanlines.extractor import Extractor
    from scanlines.io import open_log
    from scanlines.runs.runner import parse_slice, select
    from scanlines.viz.figures import save
    from scanlines.viz.scans import plot_extraction, plot_grid

    if (scan is None) == (scans is None):
        raise ParameterError("give exactly one of --scan INDEX or --scans N|START:STOP[:STEP]")
    selection = slice(scan, scan + 1) if scan is not None else parse_slice(scans)
    method, preset, params = method_options(method, preset, param, config)
    extractor = Extractor(method, preset, **params)
    writable(output, overwrite)
    options = reader_options(
        fov, angle_convention, topic, angle_min, angle_increment, range_max=range_max
    )
    with open_log(log, options=options) as reader:
        chosen, selected = [], 0
        for index, item in select(reader.enumerate(), selection):
            selected += 1
            if len(chosen) < max_pages * PANELS_PER_PAGE:
                chosen.append((item, extractor(item), f"{log.name} #{index}"))
    if not chosen:
        raise ParameterError(f"no scan of {log} falls in the selection")
    if scan is not None:
        typer.echo(f"figure: {save(plot_extraction(*chosen[0][:2], title=chosen[0][2]), output)}")
        return
    pages = [chosen[k : k + PANELS_PER_PAGE] for k in range(0, len(chosen), PANELS_PER_PAGE)]
    paths = [_page_path(output, number, len(pages)) for number in range(1, len(pages) + 1)]
    for path in paths[1:]:
        writable(path, overwrite)
    for page, path in zip(pages, paths, strict=True):
        save(plot_grid(page), path)
    left_out = (
        f"; {selected - len(chosen)} more selected, past --max-pages"
        if selected > len(chosen)
        else ""
    )
    typer.echo(
        f"drew {len(chosen)} scans ({chosen[0][2]} .. {chosen[-1][2]}) on {len(pages)} "
        f"page(s){left_out}"
    )
    for path in paths:
        typer.echo(f"figure: {path}")


PANELS_PER_PAGE = 12


def _page_path(output: Path, number: int, pages: int) -> Path:
    """``plot.png`` for page 1, ``plot-2.png``... for the next ones."""
    if number == 1:
        return output
    return output.with_name(f"{output.stem}-{number}{output.suffix}")


def sample_command(
    name: Annotated[
        str | None, typer.Argument(help="intel, freiburg or urg; none: list them all.")
    ] = None,
) -> None:
    from scanlines.data import SAMPLES, sample

    if name is not None:
        if name not in SAMPLES:
            from scanlines.errors import ParameterError

            raise ParameterError(f"no sample {name!r}; samples: {', '.join(SAMPLES)}")
        typer.echo(str(sample(name)))
        return
    for known in SAMPLES:
        typer.echo(f"{known:<9} {sample(known)}")


def demo_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Folder for the results.")] = Path(
        "scanlines-demo"
    ),
) -> None:
    from scanlines.data import sample
    from scanlines.extractor import Extractor
    from scanlines.io import open_log
    from scanlines.runs.runner import default_jobs, run_log_to_file, select
    from scanlines.viz.figures import save
    from scanlines.viz.scans import plot_grid

    log = sample("intel")
    extractor = Extractor(sensor_profile=profile_for_run(log, {}, slice(None), None))
    output.mkdir(parents=True, exist_ok=True)  # the demo's own folder, replaced each time
    jsonl = output / "intel.jsonl"
    with open_log(log) as reader:
        summary = run_log_to_file(
            reader, extractor, jsonl, input_name=log.name, jobs=default_jobs(), overwrite=True
        )
        panels = [
            (s, extractor(s), f"Intel #{i}")
            for i, s in select(reader.enumerate(), slice(0, None, 50))
        ]
    figure = save(plot_grid(panels[:6]), output / "intel.png")
    _print_summary(summary, jsonl)
    typer.echo(f"features: {jsonl.resolve()}")
    typer.echo(f"figure:   {figure.resolve()}")
