"""The ``scanlines`` command: a thin layer over the library.

Each command lives in its own module and only parses options, calls the
library and prints. Errors a user can cause (bad files, records, parameters)
end with one line on stderr and exit code 2 (see :func:`scanlines.cli.common.guarded`);
Ctrl-C and SIGTERM end with one line and exit code 130 or 143, at any moment,
including while the command starts (:func:`main` takes the signals before it imports
the commands and numba).
"""

from __future__ import annotations

import sys
from typing import Any

__all__ = ["app", "main"]


def main() -> None:
    """Console entry point: SIGINT and SIGTERM stop a command cleanly (exit 130, 143)."""
    from scanlines.interrupts import any_terminated, handle_signals, ignore_signals, is_interrupt

    handle_signals()
    try:
        from scanlines.cli.commands import app

        app()
    except SystemExit:
        ignore_signals()
        raise
    except BaseException as stop:  # an interrupt while starting, before a command runs
        if not is_interrupt(stop):
            raise
        ignore_signals()
        terminated = any_terminated(stop)
        print(f"scanlines: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
        sys.exit(143 if terminated else 130)


def __getattr__(name: str) -> Any:
    if name == "app":
        from scanlines.cli.commands import app

        return app
    raise AttributeError(f"module 'scanlines.cli' has no attribute {name!r}")
