"""Option parsing shared by the commands."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from typing import Any, TypeVar

import typer

from scanlines.errors import ParameterError, ScanlinesError

F = TypeVar("F", bound=Callable[..., Any])

INPUT_ERROR = 2


def guarded(command: F) -> F:
    """Turn an input error raised by ``command`` into one line on stderr and exit code 2."""

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return command(*args, **kwargs)
        except (ScanlinesError, OSError, EOFError) as error:
            print(f"scanlines: error: {error}", file=sys.stderr)
            raise typer.Exit(INPUT_ERROR) from None

    return wrapper  # type: ignore[return-value]


def note_first_compilation() -> None:
    """Say on stderr why the first run after an install or upgrade waits (numba compiling)."""
    from scanlines._jit import cache_is_cold

    if cache_is_cold():
        print(
            "scanlines: first run: compiling the extraction kernels (about a minute at most, "
            "once; cached for later runs)",
            file=sys.stderr,
        )


def parse_params(pairs: list[str] | None) -> dict[str, Any]:
    """``["k=3", "fit=tls"]`` -> ``{"k": "3", "fit": "tls"}`` (values validated by the method)."""
    params: dict[str, Any] = {}
    for pair in pairs or []:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise ParameterError(f"--param takes NAME=VALUE, got {pair!r}")
        params[name.strip()] = value.strip()
    return params
