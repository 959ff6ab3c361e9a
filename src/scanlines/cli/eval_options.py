"""The options every ``scanlines eval`` subcommand shares: method specs, the output folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

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


MethodsOption = Annotated[list[str] | None, typer.Option("--method", "-m", help=SPEC_HELP)]
ConfigsOption = Annotated[
    list[Path] | None, typer.Option("--config", metavar="FILE", help=CONFIG_HELP)
]
OutOption = Annotated[Path, typer.Option(help="Folder for CSV, JSON and figures.")]
EvalProfileOption = Annotated[
    Path | None,
    typer.Option(
        "--sensor-profile",
        help="Sensor profile (`scanlines calibrate`) for every extraction; default: measured "
        "from the log.",
    ),
]


def method_specs(method: list[str] | None, config: list[Path] | None) -> tuple:
    """The specs of ``--method`` and ``--config``: the configurations, then the methods
    (default adaptive when neither is given)."""
    from scanlines.evaluation.specs import parse_specs

    configured = config_specs(config or [])
    return parse_specs([*configured, *(method or ([] if configured else ["adaptive"]))])


def config_specs(paths: list[Path]) -> list:
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


def echo_written(paths: list[Path]) -> None:
    """One ``wrote PATH`` line per output."""
    for path in paths:
        typer.echo(f"wrote {path}")
