"""The command line run inside the test process, as a shell would run it, without starting one."""

from __future__ import annotations

import contextlib
import traceback
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Ran:
    """What a command left: its exit code and its two streams (as ``subprocess.run``)."""

    returncode: int
    stdout: str
    stderr: str


def scanlines(*args: object, cwd: Path | None = None, columns: int | None = None) -> Ran:
    """``scanlines ARGS`` in this process (``columns``: the terminal width tables are
    drawn to); an exception escaping the command is a traceback on stderr and exit code
    1, as in a process of its own."""
    from typer.testing import CliRunner

    from scanlines.cli import app

    with contextlib.chdir(cwd) if cwd is not None else contextlib.nullcontext():
        env = None if columns is None else {"COLUMNS": str(columns)}
        result = CliRunner().invoke(app, [str(arg) for arg in args], env=env)
    stderr = result.stderr
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        stderr += "".join(traceback.format_exception(result.exception))
    return Ran(result.exit_code, result.stdout, stderr)


def all_commands() -> dict:
    """Every command of the application by the words that run it (a group's subcommands as
    ``"eval real"``...)."""
    import typer

    from scanlines.cli import app

    out = {}
    for name, command in typer.main.get_command(app).commands.items():
        for sub, subcommand in getattr(command, "commands", {}).items():
            out[f"{name} {sub}"] = subcommand
        if command.callback is not None and not hasattr(command, "commands"):
            out[name] = command
    return out
