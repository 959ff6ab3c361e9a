"""``scanlines eval real LOG...``: the scan-to-scan repeatability of methods on real logs."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from scanlines.cli.common import NPZ_HELP, RangeMaxOption, ScansOption, guarded
from scanlines.cli.eval_options import (
    ConfigsOption,
    EvalProfileOption,
    MethodsOption,
    OutOption,
    echo_written,
    method_specs,
)
from scanlines.reader_options import parse_scans

if TYPE_CHECKING:
    from scanlines.evaluation.repeatability import RepeatabilityResult
    from scanlines.sensor.profile import SensorProfile

LogsArgument = Annotated[
    list[Path],
    typer.Argument(
        metavar="LOG...",
        help="Real logs (any format 'scanlines info' reads): the scan-to-scan repeatability of "
        "the methods (label-free; pairs 1-3 records apart registered by ICP from the log's "
        "poses, or ICP alone), with the strict measure and the fidelity of long segments. "
        "Writes repeatability.csv, repeatability_pairs.csv and repeatability.json into --out. "
        + NPZ_HELP,
    ),
]
PairsOption = Annotated[
    int | None,
    typer.Option(
        "--pairs",
        min=1,
        help="Score N used pairs spread evenly over each log (the strict "
        "measure's 200, say; the candidates are cut into N slots, each registered in turn "
        "until one pair is used); default every pair.",
    ),
]
BareOption = Annotated[
    bool,
    typer.Option(
        "--bare",
        help="The bare mode. Each method extracts with one Extractor() and no "
        "sensor profile, as extract(scan), a bare Extractor and the ROS 2 node without "
        "--sensor-profile do, fed the scans of the scored pairs in log order. Default (the "
        "profiled mode): every method with the sensor profile measured from the log's first "
        "scans, as `scanlines run` does.",
    ),
]


def register(group: typer.Typer) -> None:
    group.command(
        "real",
        help="The scan-to-scan repeatability of methods on real logs, no labels needed: "
        "pairs of nearby scans registered, the segments of one compared with the other's.",
    )(guarded(real_command))


def real_command(
    logs: LogsArgument,
    method: MethodsOption = None,
    config: ConfigsOption = None,
    scans: ScansOption = None,
    pairs: PairsOption = None,
    bare: BareOption = False,
    sensor_profile: EvalProfileOption = None,
    out: OutOption = Path("scanlines-eval"),
    range_max: RangeMaxOption = None,
) -> None:
    from scanlines.errors import ParameterError
    from scanlines.evaluation.repeatability import write_results
    from scanlines.sensor.profile import read_profile

    specs = method_specs(method, config)
    if any(spec.is_truth for spec in specs):
        raise ParameterError("'truth' needs simulated scenes; real logs have no truth")
    if bare and sensor_profile is not None:
        raise ParameterError("--bare extracts with no sensor profile; it excludes --sensor-profile")
    profile = None if sensor_profile is None else read_profile(sensor_profile)
    selection = parse_scans(scans)
    results = [
        repeatability_with_progress(
            log, specs, selection, profile, pairs, bare, range_max=range_max
        )
        for log in logs
    ]
    echo_written(write_results(results, out))


def repeatability_with_progress(
    log: Path,
    specs,
    scans: slice | int | None,
    profile: SensorProfile | None = None,
    pairs: int | None = None,
    bare: bool = False,
    *,
    range_max: float | None = None,
) -> RepeatabilityResult:
    """The repeatability of ``specs`` on ``log``, with a progress bar; prints its table."""
    from scanlines.cli.eval_reports import _print_repeatability
    from scanlines.cli.progress import progress
    from scanlines.evaluation.repeatability import RepeatTolerances, repeatability

    tol = RepeatTolerances(max_pairs=pairs)
    with progress(f"{log.name}: pairs, then scans per method", unit="steps") as tick:
        result = repeatability(
            log, specs, scans, tol=tol, on_progress=tick.update, sensor_profile=profile, bare=bare,
            **({} if range_max is None else {"range_max": range_max}),
        )  # fmt: skip
    _print_repeatability(result)
    return result
