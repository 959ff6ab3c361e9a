"""``scanlines compile``: compile every kernel ahead of time (container images, CI caches)."""

from __future__ import annotations

import time
from typing import Annotated

import typer

from scanlines.cli.common import guarded, jobs_option


def register(app: typer.Typer) -> None:
    app.command(
        "compile",
        help="Compile the kernels now (cached on disk), so later runs start at once: "
        "for container images and CI caches.",
    )(guarded(compile_command, show_compilation=False))


def compile_command(
    method: Annotated[
        list[str] | None,
        typer.Option("--method", "-m", help="Only this method, repeatable (default: all)."),
    ] = None,
    jobs: Annotated[
        int | None,
        typer.Option("--jobs", "-j", help="Processes compiling at once (default: every core)."),
    ] = None,
) -> None:
    from scanlines._jit import COMPILED, cache_root
    from scanlines.warm import compile_kernels

    if not COMPILED:
        typer.echo("numba is disabled (NUMBA_DISABLE_JIT): nothing to compile")
        return
    started = time.perf_counter()

    def done(name: str, seconds: float) -> None:
        typer.echo(f"{name}: {seconds:.1f} s", err=True)

    compile_kernels(method or None, jobs_option(jobs), on_done=done)
    typer.echo(f"kernels ready in {time.perf_counter() - started:.1f} s, cached in {cache_root()}")
