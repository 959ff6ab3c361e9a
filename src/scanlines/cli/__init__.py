"""The ``scanlines`` command: a thin layer over the library.

Each command lives in its own module and only parses options, calls the
library and prints. Errors a user can cause (bad files, records, parameters)
end with one line on stderr and exit code 2 (see :func:`scanlines.cli.common.guarded`).
"""

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


def main() -> None:
    """Console entry point."""
    app()
