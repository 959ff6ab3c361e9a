"""The ``scanlines`` command's typer application: every command registered."""

from __future__ import annotations

import typer

from scanlines.cli import bench, compile, evaluate, extract, logs, reproduce

app = typer.Typer(
    name="scanlines",
    help="Line segments, breakpoints and corners from 2D LiDAR scans.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@app.callback()
def root() -> None:
    """Line segments, breakpoints and corners from 2D LiDAR scans."""


extract.register(app)
logs.register(app)
evaluate.register(app)
bench.register(app)
reproduce.register(app)
compile.register(app)
