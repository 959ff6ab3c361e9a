"""``scanlines eval --real LOG``: the options and the run of the repeatability measure."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from scanlines.cli.common import NPZ_HELP

if TYPE_CHECKING:
    from scanlines.evaluation.repeatability import RepeatabilityResult
    from scanlines.sensor.profile import SensorProfile

RealOption = Annotated[
    list[Path] | None,
    typer.Option(
        "--real",
        help="A real log (any format 'scanlines info' reads), repeatable: measure the "
        "scan-to-scan repeatability of the methods instead (label-free; pairs 1-3 records "
        "apart registered by ICP from the log's poses, or ICP alone), with the strict measure "
        "and the fidelity of long segments. Writes repeatability.csv, "
        "repeatability_pairs.csv and repeatability.json into --out. " + NPZ_HELP,
    ),
]
PairsOption = Annotated[
    int | None,
    typer.Option(
        "--pairs",
        min=1,
        help="With --real: score N used pairs spread evenly over each log (the strict "
        "measure's 200, say; the candidates are cut into N slots, each registered in turn "
        "until one pair is used); default every pair.",
    ),
]
BareOption = Annotated[
    bool,
    typer.Option(
        "--bare",
        help="With --real: the bare mode. Each method extracts with one Extractor() and no "
        "sensor profile, as extract(scan), a bare Extractor and the ROS 2 node without "
        "--sensor-profile do, fed the scans of the scored pairs in log order. Default (the "
        "profiled mode): every method with the sensor profile measured from the log's first "
        "scans, as `scanlines run` does.",
    ),
]


def check_bare(bare: bool, real: list[Path] | None, sensor_profile: Path | None) -> None:
    """``--bare`` goes with ``--real`` and without ``--sensor-profile``."""
    from scanlines.errors import ParameterError

    if bare and not real:
        raise ParameterError("--bare is a mode of --real LOG; give --real")
    if bare and sensor_profile is not None:
        raise ParameterError("--bare extracts with no sensor profile; it excludes --sensor-profile")


def repeatability_with_progress(
    log: Path,
    specs,
    scans: int | None,
    profile: SensorProfile | None = None,
    pairs: int | None = None,
    bare: bool = False,
    *,
    range_max: float | None = None,
) -> RepeatabilityResult:
    """The repeatability of ``specs`` on ``log``, with a progress bar; prints its table."""
    from scanlines.cli.eval_reports import _print_repeatability, _progress
    from scanlines.evaluation.repeatability import RepeatTolerances, repeatability

    tol = RepeatTolerances(max_pairs=pairs)
    with _progress(f"{log.name}: pairs, then scans per method", unit="steps") as advance:
        result = repeatability(
            log, specs, scans, tol=tol, on_progress=advance, sensor_profile=profile, bare=bare,
            **({} if range_max is None else {"range_max": range_max}),
        )  # fmt: skip
    _print_repeatability(result)
    return result
