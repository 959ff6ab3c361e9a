"""``scanlines map LOG --out FILE``: the segments of every scan fused into a line map."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from scanlines.cli.common import (
    ConfigMethodOption,
    ConfigOption,
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
    reader_options,
)
from scanlines.reader_options import ReaderOptions

OUT_HELP = "The map: .geojson, .svg, .dxf (needs ezdxf) or .json (with covariances)."
PosesOption = Annotated[
    Path | None,
    typer.Option(
        "--poses",
        help="A trajectory file (TUM: timestamp tx ty tz qx qy qz qw) giving each scan's pose; "
        "default: the log's poses, else scan registration as odometry.",
    ),
]
MinScansOption = Annotated[
    int | None,
    typer.Option(
        "--min-scans", min=1, help="Lines seen by fewer scans are dropped as clutter (default 3)."
    ),
]
MapPosesOption = Annotated[
    Path | None, typer.Option("--poses", help="A TUM trajectory file of the log's poses.")
]
AlignOption = Annotated[
    bool,
    typer.Option(
        "--align",
        help="Track each scan on the map so far before fusing it (as `scanlines map "
        "--align`, the loops closed); the held-out scans are then scored at their predicted "
        "poses (moved with the optimised ones) and also localised on the finished map.",
    ),
]
TrackOption = Annotated[
    bool,
    typer.Option(
        "--align",
        help="Track: each scan's pose predicted by composing the odometry increment (of the "
        "log's poses, --poses or scan registration) onto the last corrected pose, then aligned "
        "to the map built so far; a scan that does not fit is kept out of the map. Off by "
        "default (corrected poses are used as given).",
    ),
]
PosesOutOption = Annotated[
    Path | None,
    typer.Option(
        "--poses-out",
        help="With --align: write the poses, optimised when the loops are closed (TUM, world "
        "frame, readable by evo), and the tracker's covariances beside it (NAME.cov.json).",
    ),
]
LoopsOption = Annotated[
    bool,
    typer.Option(
        "--loops/--no-loops",
        help="With --align: close the loops (a pose graph of the tracked poses and the "
        "verified loop closures, optimised; the map fused again from the optimised poses). "
        "On by default.",
    ),
]


def register(app: typer.Typer) -> None:
    app.command(
        "map",
        help="Build a line map from a log: every scan's segments moved into the world by the "
        "log's poses (or --poses, or scan registration) and fused into map lines.",
    )(guarded(map_command))


def register_eval(group: typer.Typer) -> None:
    group.command(
        "map",
        help="Score a line map: built from every scan of LOG but each 10th (`scanlines map`), "
        "scored on those: coverage of their returns, median distance, map lines per 100 m and "
        "per segment, the loop test. Writes map_eval.json into --out.",
    )(guarded(eval_map_command))


def eval_map_command(
    log: LogArgument,
    method: Annotated[
        list[str] | None,
        typer.Option("--method", "-m", help="The method spec scored (one; default adaptive)."),
    ] = None,
    config: Annotated[
        list[Path] | None,
        typer.Option("--config", metavar="FILE", help="An extraction configuration instead."),
    ] = None,
    scans: ScansOption = None,
    sensor_profile: ProfileOption = None,
    poses: MapPosesOption = None,
    align: AlignOption = False,
    loops: LoopsOption = True,
    out: Annotated[Path, typer.Option(help="Folder for map_eval.json.")] = Path("scanlines-eval"),
    range_max: RangeMaxOption = None,
) -> None:
    from scanlines.cli.eval_options import method_specs
    from scanlines.errors import ParameterError

    specs = method_specs(method, config)
    if len(specs) > 1:
        raise ParameterError("eval map scores one method: give one --method or one --config")
    evaluate_map_command(
        log, specs[0], scans, sensor_profile, poses, out, align, range_max=range_max, loops=loops
    )


def map_command(
    log: LogArgument,
    out: Annotated[Path, typer.Option(help=OUT_HELP)],
    poses: PosesOption = None,
    min_scans: MinScansOption = None,
    scans: ScansOption = None,
    method: ConfigMethodOption = None,
    preset: PresetOption = None,
    param: ParamOption = None,
    config: ConfigOption = None,
    sensor_profile: ProfileOption = None,
    plot: Annotated[
        Path | None, typer.Option(help="Also draw the map (PNG, PDF, SVG figure).")
    ] = None,
    overwrite: OverwriteOption = False,
    on_error: OnErrorOption = "fail",
    max_beams: MaxBeamsOption = None,
    range_max: RangeMaxOption = None,
    topic: TopicOption = None,
    align: TrackOption = False,
    poses_out: PosesOutOption = None,
    loops: LoopsOption = True,
) -> None:
    from scanlines.cli.common import writable
    from scanlines.errors import ParameterError
    from scanlines.map.export import check_map_format, naming_output, write_map

    check_map_format(out)  # an unknown suffix (or DXF without ezdxf) before the log is read
    if poses_out is not None and not align:
        raise ParameterError("--poses-out writes the tracked poses; it needs --align")
    writable(out, overwrite)
    writable(plot, overwrite)
    writable(poses_out, overwrite)
    if poses_out is not None:
        writable(poses_out.with_name(poses_out.stem + ".cov.json"), overwrite)
    options = reader_options(
        topic=topic, on_error=on_error, max_beams=max_beams, range_max=range_max
    )
    prepared = prepare(log, options, poses, min_scans, method, preset, param, config,
                       sensor_profile, scans)  # fmt: skip
    closed = None
    if align:
        from scanlines.map.tracking import TrackSettings

        prepared["track"] = TrackSettings()
    if align and loops and loops_available():
        from scanlines.cli.loops import run_closed_build

        build, closed = run_closed_build(log, options, prepared, scans)
    else:
        build = run_build(log, options, prepared, scans)
    lines = build.line_map.lines()
    meta = map_meta(log, build, prepared)
    if closed is not None:
        from scanlines.map.loopmap import loop_summary

        meta["loops"] = loop_summary(build, closed)
    write_map(lines, out, meta=meta, overwrite=overwrite)
    if plot is not None:
        from scanlines.cli.loops import plot_closed
        from scanlines.viz.figures import save
        from scanlines.viz.maps import plot_map

        with naming_output(plot, "the figure"):
            if closed is None:
                save(plot_map(lines, title=f"line map of {log.name}"), plot)
            else:
                save(plot_closed(lines, build, closed, f"line map of {log.name}"), plot)
        typer.echo(f"figure: {plot}")
    typer.echo(
        f"{len(lines)} map lines from {build.segments} segments of {build.scans} scans "
        f"({build.poses}); wrote {out}"
    )
    if build.pose_note:
        typer.echo(f"poses: {build.pose_note}", err=True)
    if build.without_pose:
        typer.echo(f"{build.without_pose} scans had no pose and were not mapped", err=True)
    if build.track is not None:
        _report_tracking(build, meta["tracking"], poses_out, closed)
    if closed is not None:
        from scanlines.cli.loops import report_loops

        report_loops(meta["loops"])


def loops_available() -> bool:
    """Whether scipy (the ``[map]`` extra) is there to close loops; else one line says so."""
    from importlib.util import find_spec

    if find_spec("scipy") is not None:
        return True
    typer.echo(
        "loops not closed: closing them needs scipy (pip install 'scanlines[map]'); "
        "the map is built from the tracked poses",
        err=True,
    )
    return False


def _report_tracking(build, summary: dict[str, Any], poses_out: Path | None, closed) -> None:
    """The summary of a tracked map: how far alignment moved the poses, the scans that did
    not fit (on stderr), and the poses written."""
    from scanlines.map.export import naming_output
    from scanlines.map.tracked import write_tracked

    def mm(spread: dict[str, float | None]) -> str:
        m, top = spread["median"], spread["max"]
        return (
            "-"
            if m is None or top is None
            else f"median {1000 * m:.1f} mm, max {1000 * top:.1f} mm"
        )

    def deg(spread: dict[str, float | None]) -> str:
        m, top = spread["median"], spread["max"]
        return "-" if m is None or top is None else f"median {m:.2f} deg, max {top:.2f} deg"

    typer.echo(
        f"tracked: {summary['aligned']} scans aligned, {summary['first_unaligned']} first "
        f"mapped at their odometry; alignment moved each pose from its prediction by "
        f"{mm(summary['correction_m'])} ({deg(summary['correction_deg'])}); from the log's "
        f"poses by {mm(summary['from_source_m'])}"
    )
    if build.not_aligned:
        typer.echo(
            f"{build.not_aligned} scans did not fit the map and were kept out of it "
            "(their poses predicted by odometry)",
            err=True,
        )
    if poses_out is not None:
        records = build.tracked
        if closed is not None:
            from scanlines.map.loopmap import closed_records

            records = closed_records(build, closed)
        with naming_output(poses_out, "the poses"):
            path, sidecar, untimed = write_tracked(records, build.frame, poses_out)
        typer.echo(f"wrote {path} and {sidecar}")
        if untimed:
            typer.echo(f"{untimed} scans had no timestamp and were left out of {path}", err=True)


def prepare(
    log: Path,
    options: ReaderOptions,
    poses: Path | None,
    min_scans: int | None,
    method: str | None,
    preset: str | None,
    param: list[str] | None,
    config: Path | None,
    sensor_profile: Path | None,
    scans: str | None,
) -> dict[str, Any]:
    """The extractor, pose source and fusion settings of a map command, every option
    checked before the log is read for the map."""
    from itertools import islice

    from scanlines.cli.common import method_options, profile_for_run
    from scanlines.extractor import Extractor
    from scanlines.io import open_log
    from scanlines.map.fusion import FusionSettings
    from scanlines.map.poses import RegistrationOdometry, choose_poses
    from scanlines.reader_options import parse_scans

    method, preset, params = method_options(method, preset, param, config)
    Extractor(method, preset, **params)  # bad parameters fail before the log is read
    settings = FusionSettings() if min_scans is None else FusionSettings(min_scans=min_scans)
    with open_log(log, options=options) as reader:
        source = choose_poses(islice(iter(reader), 10), poses)
    if isinstance(source, RegistrationOdometry):
        typer.echo(f"poses: {log.name} carries none; {source.name}", err=True)
    selection = parse_scans(scans)
    profile = profile_for_run(log, options, selection, sensor_profile)
    extractor = Extractor(method, preset, sensor_profile=profile, **params)
    return {"extractor": extractor, "poses": source, "settings": settings, "profile": profile}


def run_build(log: Path, options: ReaderOptions, prepared: dict[str, Any], scans: str | None):
    from scanlines.cli.progress import progress
    from scanlines.io import open_log
    from scanlines.map import build_map
    from scanlines.reader_options import parse_scans, select_scans
    from scanlines.runs.runner import selected_count

    selection = parse_scans(scans)
    with open_log(log, options=options) as reader:
        indexed = select_scans(reader.enumerate(), selection)
        total = selected_count(reader.scans_in_file, selection)
        what = "tracking and mapping" if prepared.get("track") else "mapping"
        with progress(f"{what} {log.name}", total) as tick:
            return build_map(
                indexed, prepared["extractor"], poses=prepared["poses"],
                settings=prepared["settings"], track=prepared.get("track"), source=str(log),
                on_scan=tick.scan,
            )  # fmt: skip


def map_meta(log: Path, build, prepared: dict[str, Any]) -> dict[str, Any]:
    extractor = prepared["extractor"]
    tracking = {}
    if build.track is not None:
        from scanlines.map.tracked import tracking_summary

        summary = tracking_summary(build.tracked, build.frame)
        tracking = {"tracking": {**summary, "settings": build.track.to_dict()}}
    return {
        **tracking,
        "log": log.name,
        "poses": build.poses,
        "poses_note": build.pose_note,
        "scans": build.scans,
        "segments": build.segments,
        "method": extractor.method,
        "fusion": prepared["settings"].to_dict(),
    }


def evaluate_map_command(
    log: Path,
    spec,
    scans: str | None,
    sensor_profile: Path | None,
    poses: Path | None,
    out: Path,
    align: bool = False,
    *,
    range_max: float | None = None,
    loops: bool = True,
) -> None:
    """``scanlines eval map LOG``: the map of every scan but each 10th, scored on those."""
    import time

    from rich.console import Console
    from rich.table import Table

    from scanlines.cli.progress import progress
    from scanlines.errors import ParameterError
    from scanlines.io import open_log
    from scanlines.map.export import dumps, naming_output
    from scanlines.map.holdout import evaluate_map
    from scanlines.map.tracking import TrackSettings
    from scanlines.outputs import write_text_atomically
    from scanlines.reader_options import parse_scans

    if spec.is_truth:
        raise ParameterError("eval map scores a method; 'truth' has no scans to map")
    params = [f"{name}={value}" for name, value in spec.params]
    options = reader_options(range_max=range_max)
    prepared = prepare(log, options, poses, None, spec.method, spec.preset, params, None,
                       sensor_profile, scans)  # fmt: skip
    profile = prepared["profile"]
    if profile is None:
        raise ParameterError(f"{log}: no sensor profile could be measured; give --sensor-profile")
    started = time.perf_counter()
    loop_settings = None
    if align and loops and loops_available():
        from scanlines.map.loops import LoopSettings

        loop_settings = LoopSettings()
    with progress(f"mapping {log.name}") as tick:
        score, build = evaluate_map(
            lambda: open_log(log, options=options), prepared["extractor"], profile.sigma_at,
            poses=prepared["poses"], settings=prepared["settings"], limit=parse_scans(scans),
            track=TrackSettings() if align else None, source=str(log), loops=loop_settings,
            on_scan=lambda stage, _index: (tick.begin(f"{stage} {log.name}"), tick.scan()),
        )  # fmt: skip
    seconds = time.perf_counter() - started
    table = Table(title=f"line map of {log.name}: {score.poses}", show_header=False)
    table.add_column("what", style="bold")
    table.add_column("value", justify="right")
    rows = [
        ("scans mapped / held out", f"{score.mapped_scans} / {score.held_out_scans}"),
        ("held-out returns", f"{score.returns}"),
        ("coverage (within max(3 sigma, 5 cm))", f"{score.coverage:.3f}"),
        ("median distance, mm", f"{1000 * score.median_distance:.1f}"),
        (
            f"2 sigma at the median range ({score.median_range:.2f} m), mm",
            f"{2000 * score.sigma_at_median_range:.1f}",
        ),
        *_localised_rows(score, build),
        ("map lines", f"{score.lines}"),
        ("segments mapped", f"{build.segments}"),
        ("segments per map line", f"{build.segments / max(score.lines, 1):.1f}"),
        ("map length, m", f"{score.map_length:.1f}"),
        ("map lines per 100 m", f"{score.lines_per_100m:.1f}"),
        ("loop: lines seen in the first and last 10 %", f"{score.loop_lines}"),
        ("build and score, s", f"{seconds:.1f}"),
    ]
    for row in rows:
        table.add_row(*row)
    Console().print(table)
    if build.pose_note:
        typer.echo(f"poses: {build.pose_note}", err=True)
    path = out / "map_eval.json"
    payload = {
        "log": log.name,
        "method": spec.text,
        **score.to_dict(),
        "poses_note": build.pose_note,
        "origin": list(build.frame.origin),
        "segments_mapped": build.segments,
        "segments_per_line": build.segments / max(score.lines, 1),
        "tracking": None if build.track is None else build.track.to_dict(),
        "scans_aligned": build.aligned,
        "scans_not_aligned": build.not_aligned,
        "seconds": seconds,
    }
    with naming_output(path, "the map's score"):
        write_text_atomically(path, dumps(payload), make_folder=True)
    typer.echo(f"wrote {path}")


def _localised_rows(score, build) -> list[tuple[str, str]]:
    """The rows of a map built with alignment: the held-out scans localised on the map."""
    if build.track is None:
        return []
    return [
        ("scans aligned while mapping", f"{build.aligned} / {build.scans}"),
        ("scans that did not fit (not mapped)", f"{build.not_aligned}"),
        ("localised: held-out scans aligned", f"{score.localised_scans}"),
        ("localised: coverage", f"{score.localised_coverage:.3f}"),
        ("localised: median distance, mm", f"{1000 * score.localised_median_distance:.1f}"),
    ]
