"""The four ways an input is read, each classified as success, clean error or defect.

Channels
--------
``library fail``
    ``list(open_log(path))``.
``library skip``
    ``open_log(path, on_error="skip")``, iterated.
``info``
    ``scanlines info PATH``, in-process with typer's ``CliRunner``.
``run``
    ``scanlines run PATH --out DIR/out.jsonl --on-error skip``, in-process.

``run mcap`` (``--out DIR/out.mcap``) is an extra channel for the corpus. The map
target's channels, ``map`` and ``eval map``, are in ``map_channels.py``; those of the
settings files (parameters, profiles, line maps) in ``file_channels.py``; the DDS target's,
``dds node`` and ``node exit``, in ``dds_target.py``. :class:`Case` (an input and its
outcomes) serves all three targets.

Outcomes
--------
``success``
    No exception (library), exit code 0 (command), and no silent loss.
``clean error``
    A :class:`~scanlines.ScanlinesError` with a one-line message naming the
    file (library); exit code 2 with one ``scanlines: error:`` line as the
    last line of stderr (command; other stderr lines may only be the
    ``sensor profile:`` notices).
``defect``
    Anything else: another exception, a multi-line message, a message not
    naming the file, a traceback or exit code 1, a *silent loss* (a file
    declaring ``scans_in_file`` scans whose scans + bad records are fewer,
    with no error raised; ``count mismatch`` when they are more), a timeout or
    a crashed worker. A
    ``RuntimeWarning`` raised in scanlines' own code (an error under the test
    suite's warning filter) makes an otherwise clean outcome a defect too.

Every channel runs in a :class:`Worker`: a long-lived subprocess with an
address-space limit, which the parent kills and restarts when a channel goes
past its timeout or the process dies. Given a :class:`~.binaries.BinaryWatch`, a worker
checks it on each start, death and timeout: a worker killed by a shared object rewritten
under it raises :class:`~.binaries.BinaryChanged` instead of reporting a ``crash``.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import resource
import shutil
import warnings
from dataclasses import asdict, dataclass, field
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from .binaries import BinaryWatch
from .file_channels import ALL_FILE_CHANNELS, file_channel
from .map_channels import MAP_CHANNELS, map_channel

CHANNELS = ("library fail", "library skip", "info", "run")
EXTRA_CHANNELS = ("run mcap",)
SUCCESS, CLEAN_ERROR, DEFECT = "success", "clean error", "defect"
DEFAULT_TIMEOUT = 20.0
DEFAULT_MEMORY_LIMIT = 3 * 2**30
STARTUP_TIMEOUT = 600.0
#: Warnings from files under this folder are scanlines' own.
OWN_CODE = f"{os.sep}scanlines{os.sep}"
#: stderr lines ``scanlines run`` may print besides its error line.
NOTICE_PREFIXES = ("sensor profile:",)


@dataclass
class Outcome:
    """What one channel did with one input."""

    channel: str
    kind: str
    error: str = ""  # exception type, or what went wrong ("silent loss", "timeout", ...)
    message: str = ""  # the first line of the message
    declared: int | None = None  # scans_in_file, when the reader reports it
    scans: int | None = None

    def __post_init__(self) -> None:
        self.message = first_line(self.message) if self.message else ""

    @property
    def summary(self) -> str:
        return f"{self.error}: {self.message}" if self.message else self.error


def first_line(text: str, limit: int = 300) -> str:
    lines = text.strip().splitlines()
    line = lines[0] if lines else "(no message)"
    return line if len(line) <= limit else line[:limit] + "..."


def all_lines(text: str, limit: int = 300) -> str:
    """A multi-line text on one line, its lines joined by `` | ``."""
    return first_line(" | ".join(text.strip().splitlines()), limit)


def type_name(exc: BaseException) -> str:
    """``ValueError``, ``struct.error``, ``zipfile.BadZipFile``..."""
    module = type(exc).__module__
    name = type(exc).__qualname__
    return name if module == "builtins" else f"{module.lstrip('_')}.{name}"


# -- the channels (run inside the worker) -------------------------------------------------


def library_channel(channel: str, path: Path) -> Outcome:
    from scanlines.errors import ScanlinesError
    from scanlines.io import open_log

    on_error = "fail" if channel == "library fail" else "skip"
    try:
        reader = open_log(path, on_error=on_error)
        for _ in reader:
            pass
        info = reader.info()
    except ScanlinesError as exc:
        message = str(exc)
        if len(message.splitlines()) > 1:
            return Outcome(channel, DEFECT, "multi-line message", all_lines(message))
        if str(path) not in message:
            return Outcome(channel, DEFECT, "message without the file path", first_line(message))
        return Outcome(channel, CLEAN_ERROR, type(exc).__name__, first_line(message))
    except Exception as exc:
        return Outcome(channel, DEFECT, type_name(exc), first_line(str(exc)))
    declared, scans = info.get("scans_in_file"), info["scans"]
    errors = info.get("bad_scan_records", info["errors"])
    if declared is not None and scans + errors != declared:
        loss = f"{scans} scans + {errors} bad records, but the file declares {declared} scans"
        return Outcome(channel, DEFECT, miscount(scans + errors, declared), loss, declared, scans)
    return Outcome(channel, SUCCESS, declared=declared, scans=scans)


def miscount(accounted: int, declared: int) -> str:
    """``silent loss`` when scans are missing, ``count mismatch`` when there are extra ones."""
    return "silent loss" if accounted < declared else "count mismatch"


def command_channel(channel: str, path: Path, workdir: Path, declared: int | None) -> Outcome:
    from typer.testing import CliRunner

    from scanlines.cli import app

    if workdir.exists():
        shutil.rmtree(workdir)
    workdir.mkdir(parents=True)
    out = workdir / ("out.mcap" if channel == "run mcap" else "out.jsonl")
    if channel == "info":
        args = ["info", str(path)]
    else:
        args = ["run", str(path), "--out", str(out), "--on-error", "skip"]
    result = CliRunner().invoke(app, args)
    if result.exit_code == 0:
        if channel == "run":
            return check_run_output(channel, out, declared)
        return Outcome(channel, SUCCESS)
    return classify_failure(channel, result)


def classify_failure(channel: str, result: Any, notices: tuple[str, ...] = ()) -> Outcome:
    """A command that did not exit 0: a clean error (exit 2, one ``scanlines: error:`` line,
    last, besides notices) or a defect."""
    stderr = result.stderr.strip().splitlines()
    if result.exit_code == 2:
        errors = [line for line in stderr if line.startswith("scanlines: error:")]
        others = [line for line in stderr if not line.startswith(NOTICE_PREFIXES + notices)]
        if len(errors) == 1 and others == errors and stderr[-1] == errors[0]:
            return Outcome(channel, CLEAN_ERROR, "exit 2", errors[0])
        return Outcome(channel, DEFECT, "exit 2 with a malformed error", all_lines(result.stderr))
    exception = result.exception
    if exception is not None and not isinstance(exception, SystemExit):
        name = f"exit {result.exit_code}: {type_name(exception)}"
        return Outcome(channel, DEFECT, name, first_line(str(exception)))
    return Outcome(channel, DEFECT, f"exit {result.exit_code}", first_line(result.stderr))


def check_run_output(channel: str, out: Path, declared: int | None) -> Outcome:
    """Scans written + records skipped (from ``<out>.meta.json``) against the declared count."""
    meta = out.with_name(out.name + ".meta.json")
    if not out.exists() or not meta.exists():
        return Outcome(channel, DEFECT, "no output", f"exit 0 but {out.name} or its meta missing")
    written = sum(1 for line in out.read_bytes().splitlines() if line.strip())
    counts = json.loads(meta.read_text())["counts"]
    skipped = counts["skipped_scan_records"]
    if declared is not None and written + skipped != declared:
        loss = f"{written} scans written + {skipped} skipped, but the file declares {declared}"
        return Outcome(
            channel, DEFECT, miscount(written + skipped, declared), loss, declared, written
        )
    return Outcome(channel, SUCCESS, declared=declared, scans=written)


def run_channel(channel: str, path: str, workdir: str, declared: int | None) -> Outcome:
    """Run one channel; a RuntimeWarning raised in scanlines' code (an error under the test
    suite's warning filter) turns an otherwise clean outcome into a defect."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if channel in MAP_CHANNELS:
            outcome = map_channel(channel, Path(path), Path(workdir))
        elif channel in ALL_FILE_CHANNELS:
            outcome = file_channel(channel, Path(path), Path(workdir))
        elif channel.startswith("library"):
            outcome = library_channel(channel, Path(path))
        else:
            outcome = command_channel(channel, Path(path), Path(workdir), declared)
    ours = [w for w in caught if issubclass(w.category, RuntimeWarning) and OWN_CODE in w.filename]
    if ours and outcome.kind != DEFECT:
        where = f"{Path(ours[0].filename).name}:{ours[0].lineno}"
        message = f"{where}: {first_line(str(ours[0].message))} (outcome: {outcome.kind})"
        return Outcome(channel, DEFECT, ours[0].category.__name__, message, outcome.declared)
    return outcome


# -- the worker process ---------------------------------------------------------------------


def serve(connection: Connection, memory_limit: int, warm_up: str | None, workdir: str) -> None:
    """The worker's loop: run each requested channel and send back its outcome."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    resource.setrlimit(resource.RLIMIT_AS, (memory_limit, memory_limit))
    if warm_up is not None:  # lazy imports done before the first timed channel
        run_channel("run", warm_up, workdir, None)
    connection.send("ready")
    while True:
        request = connection.recv()
        if request is None:
            return
        try:
            outcome = run_channel(**request)
        except Exception as exc:  # a bug of these checks, reported rather than hidden
            error = f"fuzzing harness: {type_name(exc)}"
            outcome = Outcome(request["channel"], DEFECT, error, first_line(str(exc)))
        connection.send(asdict(outcome))


class Worker:
    """A subprocess running channels one at a time, restarted after a timeout or crash.

    Parameters
    ----------
    workdir:
        A folder of its own for command outputs.
    warm_up:
        An input the worker runs once at start-up (untimed), to load the kernels.
    watch:
        The campaign's shared objects, checked when the worker starts, dies or times out.
    """

    def __init__(
        self,
        workdir: Path,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        memory_limit: int = DEFAULT_MEMORY_LIMIT,
        warm_up: Path | None = None,
        watch: BinaryWatch | None = None,
    ) -> None:
        self.workdir = workdir
        self.watch = watch
        self.timeout = timeout
        self.memory_limit = memory_limit
        self.warm_up = None if warm_up is None else str(warm_up)
        self.process: Any = None
        self.connection: Connection | None = None

    def check_binaries(self, when: str) -> None:
        if self.watch is not None:
            self.watch.check(when)

    def start(self) -> None:
        self.check_binaries("a worker starting")
        context = multiprocessing.get_context("spawn")
        self.connection, child = context.Pipe()
        self.process = context.Process(
            target=serve,
            args=(child, self.memory_limit, self.warm_up, str(self.workdir / "warm-up")),
            daemon=True,
        )
        self.process.start()
        child.close()
        try:
            ready = self.connection.poll(STARTUP_TIMEOUT) and self.connection.recv() == "ready"
        except (EOFError, OSError):
            ready = False
        if not ready:
            self.stop()
            self.check_binaries("a worker did not start")
            raise RuntimeError("the fuzzing worker did not start")

    def stop(self) -> None:
        if self.process is not None:
            self.process.kill()
            self.process.join()
        self.process = self.connection = None

    def close(self) -> None:
        if self.process is not None and self.process.is_alive():
            assert self.connection is not None
            self.connection.send(None)
            self.process.join(5)
        self.stop()

    def run(self, channel: str, path: Path, declared: int | None = None) -> Outcome:
        if self.process is None or not self.process.is_alive():
            self.stop()
            self.start()
        assert self.connection is not None
        request = {"channel": channel, "path": str(path), "workdir": str(self.workdir / "out")}
        self.connection.send(request | {"declared": declared})
        if not self.connection.poll(self.timeout):
            self.stop()
            self.check_binaries(f"a worker timed out on {path}")
            return Outcome(channel, DEFECT, "timeout", f"no answer within {self.timeout:g} s")
        try:
            return Outcome(**self.connection.recv())
        except (EOFError, OSError):
            self.process.join(5)
            exitcode = self.process.exitcode
            self.stop()
            self.check_binaries(f"a worker died (exit code {exitcode}) on {path}")
            return Outcome(channel, DEFECT, "crash", f"the worker died (exit code {exitcode})")

    def run_all(self, path: Path, channels: tuple[str, ...] = CHANNELS) -> list[Outcome]:
        """Every channel on ``path``; ``run`` checks against the count ``library skip`` saw."""
        outcomes: list[Outcome] = []
        declared = None
        for channel in channels:
            outcome = self.run(channel, path, declared)
            declared = outcome.declared if outcome.declared is not None else declared
            outcomes.append(outcome)
        return outcomes

    def __enter__(self) -> Worker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass
class Case:
    """One mutated input and what the channels made of it."""

    index: int
    seed_name: str
    plan: str
    path: Path
    outcomes: list[Outcome] = field(default_factory=list)
    saved: Path | None = None
    channels: tuple[str, ...] | None = None  # None: those of the run

    @property
    def defects(self) -> list[Outcome]:
        return [o for o in self.outcomes if o.kind == DEFECT]

    def saved_name(self, seed: int) -> str:
        """``format--mutator--seedS-index`` plus the seed's suffixes."""
        suffix = "".join(self.path.suffixes)
        return (
            f"{self.seed_name}--{self.plan.replace('/', '-')}--seed{seed}-{self.index:05d}{suffix}"
        )
