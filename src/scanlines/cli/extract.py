"""``scanlines extract FILE``: features of one scan from a CSV or NPZ file."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import typer

from scanlines.cli.common import (
    NPZ_HELP,
    ConfigOption,
    OverwriteOption,
    guarded,
    method_options,
    writable,
)
from scanlines.errors import LogFormatError

FILE_HELP = f"One scan: CSV (one row of ranges) or NPZ. {NPZ_HELP}"


def register(app: typer.Typer) -> None:
    app.command("extract", help="Extract segments, breakpoints and corners from one scan.")(
        guarded(extract_command)
    )


def extract_command(
    file: Annotated[Path, typer.Argument(help=FILE_HELP)],
    method: Annotated[
        str | None,
        typer.Option(help="Extraction method.", show_default="the --config file's, else adaptive"),
    ] = None,
    preset: Annotated[str | None, typer.Option(help="Named parameter set, e.g. paper.")] = None,
    param: Annotated[
        list[str] | None, typer.Option("--param", help="NAME=VALUE, repeatable.")
    ] = None,
    config: ConfigOption = None,
    angle_min: Annotated[
        float | None, typer.Option("--angle-min", help="CSV: first bearing, degrees.")
    ] = None,
    angle_increment: Annotated[
        float | None, typer.Option("--angle-increment", help="CSV: bearing step, degrees.")
    ] = None,
    range_max: Annotated[
        float | None, typer.Option("--range-max", help="CSV: largest valid range, metres.")
    ] = None,
    plot: Annotated[Path | None, typer.Option(help="Write a figure (PNG, PDF, SVG).")] = None,
    overwrite: OverwriteOption = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of tables.")] = False,
    sensor_profile: Annotated[
        Path | None,
        typer.Option(
            "--sensor-profile",
            help="Sensor profile from `scanlines calibrate` (default: the scan's own noise).",
        ),
    ] = None,
) -> None:
    from scanlines.extractor import Extractor

    method, preset, params = method_options(method, preset, param, config)
    extractor = Extractor(method, preset, sensor_profile=sensor_profile, **params)
    writable(plot, overwrite)  # a missing folder or a taken figure, before any work
    scan, notes = load_one_scan(file, angle_min, angle_increment, range_max)
    result = extractor(scan)
    if plot is not None:
        from scanlines.viz.figures import save
        from scanlines.viz.scans import plot_extraction

        save(plot_extraction(scan, result, title=file.name), plot)
    if as_json:
        payload = {"file": str(file), "beams": len(scan), **result.to_dict()}
        if notes:
            payload["notes"] = notes
        typer.echo(json.dumps(payload, indent=2))
    else:
        print_tables(file, scan, result)
        for note in notes:
            typer.echo(f"note: {note}")
        if plot is not None:
            typer.echo(f"figure: {plot}")


def load_one_scan(
    file: Path, angle_min: float | None, angle_increment: float | None, range_max: float | None
):
    """The only scan of ``file`` (CSV angles given in degrees on the command line), and
    the reader's notes (an NPZ's no-return code read as no return, say)."""
    from scanlines.io import open_log

    options: dict[str, float] = {}
    if angle_min is not None:
        options["angle_min"] = math.radians(angle_min)
    if angle_increment is not None:
        options["angle_increment"] = math.radians(angle_increment)
    if range_max is not None:
        options["range_max"] = range_max
    kind = single_scan_format(file)
    if kind == "npz" and options:
        raise LogFormatError(
            "--angle-min/--angle-increment/--range-max are for CSV files", path=file
        )
    reader = open_log(file, format=kind, **options)
    scans = iter(reader)
    scan = next(scans, None)
    if scan is None:
        raise LogFormatError("no scan in the file", path=file)
    if next(scans, None) is not None:
        raise LogFormatError("holds more than one scan; use 'scanlines run' for logs", path=file)
    return scan, reader.notes


#: The log formats ``extract`` refuses, as its message names them.
LOG_NAMES = {"carmen": "CARMEN", "rosbag": "ROS bag", "coreslam": "CoreSLAM (.dat)"}


def single_scan_format(file: Path) -> str:
    """``"npz"`` or ``"csv"``: the format of a file ``extract`` reads; a log of another
    format is refused naming the commands that read logs."""
    from scanlines.io import detect_format

    if file.name.lower().endswith(".npz"):
        return "npz"
    try:
        found = detect_format(file)
    except LogFormatError:
        return "csv"  # the CSV reader says what is wrong with it
    if found in ("csv", "npz"):
        return found
    raise LogFormatError(
        f"a {LOG_NAMES.get(found, found)} log, not a single scan (.npz or .csv): "
        "`scanlines plot LOG --scan N` draws one of its scans, `scanlines run LOG` extracts "
        "them all",
        path=file,
    )


def print_tables(file: Path, scan, result) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    table = Table(title=f"{file.name}: {len(scan)} beams, method {result.method}")
    for column in (
        "#",
        "first",
        "last",
        "points",
        "rho (m)",
        "alpha (deg)",
        "length (m)",
        "rms (m)",
    ):
        table.add_column(column, justify="right")
    for k, s in enumerate(result.segments):
        table.add_row(
            str(k),
            str(s.first),
            str(s.last),
            str(s.n_points),
            f"{s.rho:.4f}",
            f"{math.degrees(s.alpha):.2f}",
            f"{s.length:.3f}",
            f"{s.rms:.4f}",
        )
    console.print(table)
    console.print(f"breakpoints ({len(result.breakpoints)}): {result.breakpoints.tolist()}")
    console.print(f"corners ({len(result.corners)}): {result.corners.tolist()}")
    if result.outliers.size:
        console.print(f"outliers ({len(result.outliers)}): {result.outliers.tolist()}")
