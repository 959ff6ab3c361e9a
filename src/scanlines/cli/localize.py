"""``scanlines localize LOG --map MAP.json --initial-pose T,X,Y,YAW --out poses.tum``."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from scanlines.cli.common import LogArgument, OverwriteOption, RangeMaxOption, guarded


def register(app: typer.Typer) -> None:
    app.command(
        "localize",
        help="Track a log on a saved line map (the .json `scanlines map` writes) from a given "
        "pose: odometry as the prior (its heading drift, scale and the sensor's lever learnt "
        "on the way), each scan's returns matched to the map's lines; writes the poses (TUM) "
        "and their covariances (NAME.cov.json).",
    )(guarded(localize_command))


def parse_initial_pose(text: str) -> tuple[float, tuple[float, float, float]]:
    """``T,X,Y,YAW`` (seconds, metres, metres, radians) as ``(t, (x, y, yaw))``."""
    from scanlines.errors import ParameterError

    fields = text.split(",")
    try:
        values = [float(v) for v in fields]
    except ValueError:
        values = []
    if len(values) != 4 or not all(math.isfinite(v) for v in values):
        raise ParameterError(
            f"--initial-pose: {text!r} is not T,X,Y,YAW (four finite numbers: the time in "
            "seconds, the position in metres, the heading in radians)"
        )
    return values[0], (values[1], values[2], values[3])


#: How far (seconds) a pose of --initial-pose-from may lie from the log's first time.
INITIAL_POSE_TOLERANCE = 0.05


def initial_pose_of(log: Path, options, given: str | None, source: Path | None):
    """``(t, (x, y, yaw))``: ``--initial-pose``, or the pose of ``--initial-pose-from`` at
    the time of the log's first scan (the nearest within :data:`INITIAL_POSE_TOLERANCE`);
    ``None`` when neither is given (the pose is searched for on the map)."""
    from scanlines.errors import ParameterError

    if given is not None and source is not None:
        raise ParameterError(
            "give one of --initial-pose T,X,Y,YAW or --initial-pose-from POSES.tum (the "
            "poses `scanlines map LOG --align --poses-out POSES.tum` writes), not both"
        )
    if given is None and source is None:
        return None
    if given is not None:
        return parse_initial_pose(given)
    from scanlines.io import open_log
    from scanlines.map.poses import read_tum

    trajectory = read_tum(source)
    with open_log(log, options=options) as reader:
        first = next((s.timestamp for s in reader if s.timestamp is not None), None)
    if first is None:
        raise ParameterError(f"{log}: no scan has a timestamp to find in {source}")
    gaps = abs(trajectory.times - first)
    nearest = int(gaps.argmin())
    if gaps[nearest] > INITIAL_POSE_TOLERANCE:
        raise ParameterError(
            f"{source}: no pose within {1000 * INITIAL_POSE_TOLERANCE:.0f} ms of the first time "
            f"of {log.name}, {first!r} s (its poses run from {float(trajectory.times[0])!r} "
            f"to {float(trajectory.times[-1])!r} s); give --initial-pose T,X,Y,YAW"
        )
    x, y, yaw = (float(v) for v in trajectory.poses[nearest])
    return first, (x, y, yaw)


def localize_command(
    log: LogArgument,
    map_file: Annotated[
        Path, typer.Option("--map", help="The line map: the .json `scanlines map` writes.")
    ],
    out: Annotated[Path, typer.Option(help="The poses (TUM); covariances in NAME.cov.json.")],
    initial_pose: Annotated[
        str | None,
        typer.Option(
            "--initial-pose",
            help="T,X,Y,YAW: where the robot stands (map frame, metres, heading in radians) "
            "at time T (seconds of the log's clock); earlier scans are skipped. A pose of "
            "the map's trajectory (`map --align --poses-out`), or one read off the map. "
            "Without it (nor --initial-pose-from) the pose is searched for on the map "
            "(global localisation) from the first scan.",
        ),
    ] = None,
    initial_pose_from: Annotated[
        Path | None,
        typer.Option(
            "--initial-pose-from",
            metavar="POSES.tum",
            help="Instead of --initial-pose: the pose at the log's first time, taken from "
            "this TUM file (the poses `map --align --poses-out` wrote for the map).",
        ),
    ] = None,
    sides: Annotated[
        bool,
        typer.Option(
            "--sides",
            help="Match a return only to a wall's face the map saw from the return's side "
            "(by default the sides the map keeps are ignored: a wall the map holds only "
            "from behind still holds the pose).",
        ),
    ] = False,
    overwrite: OverwriteOption = False,
    range_max: RangeMaxOption = None,
) -> None:
    import time

    from scanlines.cli.common import reader_options, writable
    from scanlines.cli.progress import progress
    from scanlines.io import open_log
    from scanlines.map.export import naming_output
    from scanlines.map.filter import FilterSettings
    from scanlines.map.localize import localize, read_line_map
    from scanlines.map.tracked import write_tracked

    options = reader_options(range_max=range_max)
    initial = initial_pose_of(log, options, initial_pose, initial_pose_from)
    writable(out, overwrite)
    writable(out.with_name(out.stem + ".cov.json"), overwrite)
    lines, frame = read_line_map(map_file)
    started = time.perf_counter()
    with (
        open_log(log, options=options) as reader,
        progress(f"localising {log.name}", reader.scans_in_file) as tick,
    ):
        settings = FilterSettings(sides=sides)
        run = localize(
            reader.enumerate(), lines, frame, initial, settings=settings, on_scan=tick.scan
        )
    seconds = time.perf_counter() - started
    if not run.tracked:
        from scanlines.errors import ParameterError

        when = "" if initial is None else f" at or after time {initial[0]!r}"
        raise ParameterError(f"{log}: no scan with a pose{when}")
    with naming_output(out, "the poses"):
        path, sidecar, _ = write_tracked(run.tracked, frame, out)
    read = len(run.tracked) + run.skipped + run.without_pose
    aligned = sum(1 for t in run.tracked if t.aligned)
    typer.echo(
        f"{len(run.tracked)} scans localised on {len(lines.rho)} map lines ({aligned} aligned), "
        + ("" if initial is None else f"{run.skipped} before time {initial[0]:g} skipped; ")
        + f"{read / seconds:.0f} scans/s; "
        f"wrote {path} and {sidecar}"
    )
    typer.echo(
        f"odometry as learnt: heading drift {math.degrees(run.drift):+.2f} deg per metre, "
        f"distance scale {100 * run.scale:+.1f} %, sensor at ({run.lever[0]:+.3f}, "
        f"{run.lever[1]:+.3f}) m on the odometry's frame"
    )
    if run.not_fit:
        typer.echo(
            f"{run.not_fit} scans did not fit the map (their poses predicted by odometry, "
            "status 'did not fit' in the covariances)",
            err=True,
        )
    _report_lost(run)
    if run.without_pose:
        typer.echo(f"{run.without_pose} scans carry no odometry pose and were left out", err=True)


def _report_lost(run) -> None:
    """Where the filter was lost and found again (stderr), and its state at the end."""
    lost = sum(1 for t in run.tracked if t.status == "lost")
    if not lost and not run.lost_at:
        return
    pairs = ", ".join(
        f"lost at scan {a}" + (f", found at {b}" if b is not None else ", not found")
        for a, b in _episodes(run.lost_at, run.found_at)
    )
    end = "lost" if run.tracked[-1].status == "lost" else "found"
    typer.echo(
        f"{lost} scans lost (status 'lost' in the covariances){': ' + pairs if pairs else ''}"
        f"; {end} at the end",
        err=True,
    )


def _episodes(lost_at: list[int], found_at: list[int]) -> list[tuple[int, int | None]]:
    """Each scan the filter declared itself lost with the next scan it was found at."""
    out = []
    for a in lost_at:
        after = [b for b in found_at if b > a]
        out.append((a, after[0] if after else None))
    return out
