"""The ``scanlines`` command: a thin layer over the library.

Each command lives in its own module and only parses options, calls the
library and prints. Errors a user can cause (bad files, records, parameters)
end with one line on stderr and exit code 2 (see :func:`scanlines.cli.common.guarded`);
Ctrl-C and SIGTERM end with one line and exit code 130 or 143, at any moment,
including while the command starts (:func:`main` takes the signals before it imports
the commands).
"""

from __future__ import annotations

import os
import sys
from typing import Any

__all__ = ["app", "main"]


def main() -> None:
    """Console entry point: SIGINT and SIGTERM stop a command cleanly (exit 130, 143)."""
    from scanlines.cli.interrupts import (
        any_terminated,
        handle_signals,
        ignore_signals,
        is_interrupt,
    )

    handle_signals()
    try:
        from scanlines.cli.commands import app

        app()
    except SystemExit as done:
        ignore_signals()
        if done.code in (INTERRUPTED, TERMINATED):
            if is_interrupt(done):  # Ctrl-C while typer parsed the options: it exits 130
                print("scanlines: interrupted", file=sys.stderr)
            _leave(done.code)
        raise
    except BaseException as stop:  # an interrupt while starting, before a command runs
        if not is_interrupt(stop):
            raise
        ignore_signals()
        terminated = any_terminated(stop)
        print(f"scanlines: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
        _leave(TERMINATED if terminated else INTERRUPTED)


INTERRUPTED, TERMINATED = 130, 143


def _leave(code: int) -> None:
    """Exit at once after an interrupt, without the interpreter's finalisation: the
    command has cleaned up (its writers deleted their temporary files); finalising the
    interpreter could only report the interrupt a second time (a daemon thread's, say)."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def __getattr__(name: str) -> Any:
    if name == "app":
        from scanlines.cli.commands import app

        return app
    raise AttributeError(f"module 'scanlines.cli' has no attribute {name!r}")
