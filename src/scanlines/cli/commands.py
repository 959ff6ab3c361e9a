"""The ``scanlines`` command's typer application: every command registered."""

from __future__ import annotations

from typing import Annotated

import typer

from scanlines.cli import bench, evaluate, extract, localize, logs, maps, ros2, view

app = typer.Typer(
    name="scanlines",
    help="Line segments, breakpoints and corners from 2D LiDAR scans.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _print_version(value: bool) -> None:
    if value:
        from scanlines import __version__

        typer.echo(f"scanlines {__version__}")
        raise typer.Exit()


@app.callback()
def root(
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            callback=_print_version,
            is_eager=True,
            help="Print the version and exit.",
        ),
    ] = False,
) -> None:
    """Line segments, breakpoints and corners from 2D LiDAR scans."""


extract.register(app)
logs.register(app)
maps.register(app)
localize.register(app)
evaluate.register(app)
bench.register(app)
view.register(app)
ros2.register(app)
