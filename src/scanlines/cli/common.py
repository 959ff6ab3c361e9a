"""Option parsing shared by the commands."""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, Literal, TypeVar

import typer

from scanlines.builtin_methods import BUILTIN_METHODS
from scanlines.cli.interrupts import Terminated, any_terminated, is_interrupt
from scanlines.errors import ParameterError, ScanlinesError
from scanlines.reader_options import SCANS_HELP, ReaderOptions

F = TypeVar("F", bound=Callable[..., Any])

INPUT_ERROR = 2
#: Exit codes of a command stopped by SIGINT (Ctrl-C) and SIGTERM: 128 + the signal.
INTERRUPTED = 130
TERMINATED = 143


#: How an NPZ without ``range_max`` is read (:mod:`scanlines.io.npz`), in the help of every
#: command that reads one.
NPZ_HELP = (
    "An .npz holds ranges, angle_min, angle_increment and range_max; without range_max "
    "(an .npz key, a .csv's '# range_max=' comment or --range-max), the largest range, where "
    "at least 1 % of the beams hold it exactly, is read as a no-return code (the SICK "
    "81.83 m), not as a wall."
)
LogArgument = Annotated[
    Path,
    typer.Argument(help=f"CARMEN log, ROS bag, .dat, .csv or .npz. {NPZ_HELP}"),
]
FovOption = Annotated[
    float | None, typer.Option("--fov", help="CARMEN FLASER: field of view, degrees.")
]
ConventionOption = Annotated[
    Literal["step", "linspace"] | None,
    typer.Option("--angle-convention", help="CARMEN FLASER: bearings by step or linspace."),
]
TopicOption = Annotated[str | None, typer.Option(help="ROS bag: the LaserScan topic.")]
AngleMinOption = Annotated[
    float | None, typer.Option("--angle-min", help="CSV: first bearing, degrees.")
]
AngleStepOption = Annotated[
    float | None, typer.Option("--angle-increment", help="CSV: bearing step, degrees.")
]
RangeMaxOption = Annotated[
    float | None,
    typer.Option(
        "--range-max",
        help="Largest valid range, metres: farther beams read as no return (CARMEN, .dat, "
        "CSV, NPZ; a bag's messages state their own). Default: the log's.",
    ),
]
OnErrorOption = Annotated[
    Literal["fail", "skip"],
    typer.Option("--on-error", help="Stop at a malformed record, or skip and count it."),
]
MaxBeamsOption = Annotated[
    int | None,
    typer.Option("--max-beams", help="Most beams in one scan (default 1,000,000).", min=1),
]
PresetOption = Annotated[str | None, typer.Option(help="Named parameter set, e.g. paper.")]
ParamOption = Annotated[list[str] | None, typer.Option("--param", help="NAME=VALUE, repeatable.")]
ScansOption = Annotated[str | None, typer.Option("--scans", help=SCANS_HELP)]
JobsOption = Annotated[
    int | None,
    typer.Option("--jobs", "-j", help="Threads extracting chunks of scans (default: every core)."),
]
ProfileOption = Annotated[
    Path | None,
    typer.Option(
        "--sensor-profile",
        help="Sensor profile from `scanlines calibrate` (default: measured from the log).",
    ),
]


def guarded(command: F) -> F:
    """Turn an input error raised by ``command`` into one line on stderr and exit code 2,
    and Ctrl-C or SIGTERM into a one-line note and exit code 130 or 143 (the interrupt's
    notes, if any, in brackets; outputs being written are deleted on the way out)."""

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            check_input_paths(kwargs)
            return command(*args, **kwargs)
        except (ScanlinesError, EOFError) as error:
            print(f"scanlines: error: {error}", file=sys.stderr)
            raise typer.Exit(INPUT_ERROR) from None
        except OSError as error:
            print(f"scanlines: error: {os_error_line(error)}", file=sys.stderr)
            raise typer.Exit(INPUT_ERROR) from None
        except (KeyboardInterrupt, Terminated) as stop:
            if not is_interrupt(stop):
                raise
            terminated = any_terminated(stop)
            notes = "; ".join(getattr(stop, "__notes__", ()))
            word = "terminated" if terminated else "interrupted"
            print(f"scanlines: {word}" + (f" ({notes})" if notes else ""), file=sys.stderr)
            raise typer.Exit(TERMINATED if terminated else INTERRUPTED) from None

    return wrapper  # type: ignore[return-value]


#: The path options a command writes (every other path option is read): checked by
#: :func:`writable` instead, never required to exist.
OUTPUT_PARAMETERS = frozenset({"out", "output", "plot", "poses_out", "save_scenes", "json_path"})


def input_paths(arguments: dict[str, Any]) -> list[tuple[str, Path]]:
    """The ``(parameter, path)`` pairs of a command's arguments that name files it reads:
    every :class:`~pathlib.Path` value (or list of them) not in :data:`OUTPUT_PARAMETERS`,
    globs left to the command that expands them."""
    found = []
    for name, value in arguments.items():
        if name in OUTPUT_PARAMETERS:
            continue
        for path in value if isinstance(value, list | tuple) else [value]:
            if isinstance(path, Path) and not any(c in str(path) for c in "*?["):
                found.append((name, path))
    return found


def check_input_paths(arguments: dict[str, Any]) -> None:
    """Every file a command reads is there and readable, before any work: else an
    :class:`OSError` naming it, which :func:`guarded` prints as ``PATH: no such file or
    directory`` (or ``PATH: permission denied``), whatever the option."""
    import errno
    import os

    for _, path in input_paths(arguments):
        if not path.exists():
            raise OSError(errno.ENOENT, os.strerror(errno.ENOENT), str(path))
        if not os.access(path, os.R_OK):
            raise OSError(errno.EACCES, os.strerror(errno.EACCES), str(path))


def os_error_line(error: OSError) -> str:
    """An :class:`OSError` in the one form of every command, ``PATH: reason``
    (``x.clf: no such file or directory``), without Python's ``[Errno 2]``."""
    import os

    if error.errno is None:
        return str(error)
    reason = os.strerror(error.errno)
    reason = reason[:1].lower() + reason[1:]
    if error.filename is None:
        return reason
    return f"{error.filename}: {reason}"


def jobs_option(jobs: int | None) -> int:
    """``--jobs``: at least 1; ``None`` is every core this process may use."""
    from scanlines.runs.runner import default_jobs

    if jobs is None:
        return default_jobs()
    if jobs < 1:
        raise ParameterError(f"--jobs must be at least 1, got {jobs}")
    return jobs


#: ``--method`` of a command that takes ``--config``: ``None`` when not given.
ConfigMethodOption = Annotated[
    str | None,
    typer.Option(
        "--method",
        metavar=f"[{'|'.join(BUILTIN_METHODS)}]",
        help="Extraction method (or one registered with scanlines.methods.register).",
        show_default="the --config file's, else adaptive",
    ),
]

OverwriteOption = Annotated[
    bool, typer.Option("--overwrite", help="Replace output files that exist already.")
]


def writable(path: Path | None, overwrite: bool, *, with_meta: bool = False) -> Path | None:
    """``path`` (an output the user named), checked before any work: its folder exists,
    and it (and its ``.meta.json``) does not, unless ``--overwrite``."""
    if path is None:
        return None
    from scanlines.io.writers import meta_path_for
    from scanlines.outputs import check_output

    companions = [meta_path_for(path)] if with_meta else []
    return check_output(path, overwrite=overwrite, companions=companions)


CONFIG_HELP = (
    "Extraction configuration: a TOML file of method, preset and a params table (as the "
    "viewer saves it). "
    "--method, --preset and --param given too override it."
)
ConfigOption = Annotated[
    Path | None, typer.Option("--config", metavar="FILE", help=CONFIG_HELP, show_default=False)
]


def method_options(
    method: str | None, preset: str | None, param: list[str] | None, config: Path | None
) -> tuple[str, str | None, dict[str, Any]]:
    """The method, preset and parameter overrides of a command: those of ``--config FILE``
    (:func:`scanlines.config.load_config`), overridden by ``--method``, ``--preset`` and
    each ``--param`` given (``None``: not given). Without a configuration, ``--method``
    defaults to ``adaptive``.

    Raises
    ------
    ParameterError
        For a configuration that cannot be read or is not valid (naming the file), or
        a ``--method`` other than the configuration's while the configuration sets a
        preset or parameters (they belong to its method).
    """
    from scanlines.config import DEFAULT_METHOD, load_config

    params = parse_params(param)
    check_method(method)
    if config is None:
        return method or DEFAULT_METHOD, preset, params
    loaded = load_config(config)
    if method is not None and method != loaded.method:
        owned = [
            what
            for what, given in (
                (f"preset {loaded.preset!r}", loaded.preset is not None and preset is None),
                (f"parameters {', '.join(loaded.params)}", bool(loaded.params)),
            )
            if given
        ]
        if owned:
            raise ParameterError(
                f"--method {method} differs from method {loaded.method!r} of {config}, whose "
                f"{' and '.join(owned)} belong to {loaded.method!r}; drop --method or --config"
            )
        return method, preset, params
    return loaded.method, loaded.preset if preset is None else preset, {**loaded.params, **params}


def check_method(method: str | None) -> None:
    """``--method``: a method's name, else one line listing them (no usage box)."""
    if method is None:
        return
    from scanlines.extractor import method_names

    names = method_names()
    if method not in names:
        raise ParameterError(f"--method {method!r} is not a method; methods: {', '.join(names)}")


def parse_params(pairs: list[str] | None) -> dict[str, Any]:
    """``["k=3", "fit=tls"]`` -> ``{"k": "3", "fit": "tls"}`` (values validated by the method)."""
    params: dict[str, Any] = {}
    for pair in pairs or []:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise ParameterError(f"--param takes NAME=VALUE, got {pair!r}")
        params[name.strip()] = value.strip()
    return params


def reader_options(
    fov: float | None = None,
    angle_convention: str | None = None,
    topic: str | None = None,
    angle_min: float | None = None,
    angle_increment: float | None = None,
    on_error: str | None = None,
    max_beams: int | None = None,
    range_max: float | None = None,
) -> ReaderOptions:
    """The reader options the user gave on the command line (angles given in degrees),
    and only those: each reader refuses the ones it does not take."""
    return ReaderOptions(
        max_beams=max_beams,
        fov=fov,
        angle_convention=angle_convention,
        topic=topic,
        angle_min=None if angle_min is None else math.radians(angle_min),
        angle_increment=None if angle_increment is None else math.radians(angle_increment),
        on_error=on_error,
        range_max=range_max,
    )


def profile_for_run(log: Path, options: ReaderOptions, selection: slice, given: Any):
    """:func:`scanlines.runs.runner.run_profile`, its note on stderr."""
    from scanlines.runs.runner import run_profile

    profile, note = run_profile(log, options, selection, given)
    if note:
        typer.echo(note, err=True)
    return profile


def with_mounting(log: Path, options: ReaderOptions, profile: Any) -> ReaderOptions:
    """:func:`scanlines.runs.runner.mounted_options`, its note on stderr."""
    from scanlines.runs.runner import mounted_options

    options, note = mounted_options(log, options, profile)
    if note:
        typer.echo(note, err=True)
    return options
