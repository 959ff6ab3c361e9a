"""The compiler of the hot path: numba when installed, plain Python otherwise.

Every kernel (a function decorated :func:`kernel`) in :mod:`scanlines.steps` and
:mod:`scanlines.methods` is written once,
in the subset of Python and numpy that numba compiles. With numba (a dependency
of the package) the kernels are compiled on first use and cached next to the
sources' fingerprint; without it (or with ``NUMBA_DISABLE_JIT=1``) the same
functions run as ordinary Python: identical results, far slower.

Each module's kernels are cached in a directory of their own, named by a hash of the
module's source and of every package module it imports, directly or not: numba checks
only the file of the function it compiles, while a kernel links kernels (and reads
constants) of the modules it imports. So an edit to one method recompiles that
method's kernels alone, and an edit to a step recompiles every method built on it.
The directories are ``<module>-<hash>`` under ``$NUMBA_CACHE_DIR`` if that variable is
set, else under ``$XDG_CACHE_HOME/scanlines`` (default ``~/.cache``).
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from scanlines._compile_watch import compile_ended, compile_started

F = TypeVar("F", bound=Callable[..., Any])

try:
    import numba
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None

__all__ = ["COMPILED", "cache_dir", "cache_root", "kernel", "kernel_seconds", "scan_kernel"]

COMPILED = numba is not None and not numba.config.DISABLE_JIT


_PACKAGE = Path(__file__).parent


def cache_root() -> Path:
    """The folder holding every module's kernel cache."""
    return Path(
        os.environ.get("NUMBA_CACHE_DIR")
        or os.path.join(
            os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "scanlines"
        )
    )


def cache_dir(module: str) -> Path:
    """The cache folder of the kernels of ``module`` (the module docstring)."""
    return cache_root() / f"{module.removeprefix('scanlines.')}-{_source_hash(module)}"


@functools.cache
def _source_hash(module: str) -> str:
    digest = hashlib.sha1()
    for path in sorted(_imported_files(module)):
        digest.update(path.relative_to(_PACKAGE.parent).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _imported_files(module: str) -> set[Path]:
    """The file of ``module`` and of every package module it imports at its top level,
    directly or through others (a module outside the package: its own file)."""
    if not module.startswith("scanlines."):
        found = sys.modules.get(module)
        path = getattr(found, "__file__", None)
        return {Path(path)} if path else set()
    files: set[Path] = set()
    waiting = [module]
    while waiting:
        path = _module_file(waiting.pop())
        if path is None or path in files:
            continue
        files.add(path)
        waiting.extend(_top_level_imports(path))
    return files


def _module_file(module: str) -> Path | None:
    base = _PACKAGE.joinpath(*module.split(".")[1:])
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


_FROM_IMPORT = re.compile(r"^from (scanlines[\w.]*) import (\([^)]*\)|[^\n]*)", re.MULTILINE)
_IMPORT = re.compile(r"^import (scanlines[\w.]*)", re.MULTILINE)


@functools.cache
def _top_level_imports(path: Path) -> list[str]:
    """The package modules ``path`` imports at column 0 (``from a import b`` names
    ``a.b`` where that is a module); imports under ``TYPE_CHECKING`` reach no kernel."""
    text = path.read_text(encoding="utf-8")
    found = _IMPORT.findall(text)
    for module, names in _FROM_IMPORT.findall(text):
        words = (name.split(" as ")[0].strip() for name in names.strip("()").split(","))
        submodules = [f"{module}.{word}" for word in words if word and word.isidentifier()]
        found += [name for name in submodules if _module_file(name)] or [module]
    return found


if numba is not None:
    import numba.core.event

    class _ClockListener(numba.core.event.Listener):
        def on_start(self, event: Any) -> None:
            _CLOCK.on_start(event)

        def on_end(self, event: Any) -> None:
            _CLOCK.on_end(event)

    class _CompileListener(numba.core.event.Listener):
        """Forwards compile events to the watchers of :mod:`scanlines._compile_watch`."""

        def on_start(self, event: Any) -> None:
            compile_started(event.data["dispatcher"].py_func.__name__)

        def on_end(self, event: Any) -> None:
            compile_ended()

    numba.core.event.register("numba:compiler_lock", _ClockListener())
    if not numba.config.DISABLE_JIT:
        numba.core.event.register("numba:compile", _CompileListener())


class _KernelClock:
    """Seconds this process spent compiling kernels or loading them from the cache.

    Numba takes its compiler lock around both (nested, per thread); the outermost
    acquisition of each thread is timed, waiting for the lock included, so that a
    thread whose call waited on another thread's compilation counts it too.
    """

    def __init__(self) -> None:
        self.seconds = 0.0  # summed over threads
        self.wall_seconds = 0.0  # while any thread compiles or waits
        self._threads = 0
        self._wall_started = 0.0
        self._lock = threading.Lock()
        self._local = threading.local()

    def on_start(self, _event: Any) -> None:
        depth = getattr(self._local, "depth", 0)
        if depth == 0:
            now = self._local.started = time.perf_counter()
            with self._lock:
                if self._threads == 0:
                    self._wall_started = now
                self._threads += 1
        self._local.depth = depth + 1

    def on_end(self, _event: Any) -> None:
        self._local.depth -= 1
        if self._local.depth == 0:
            now = time.perf_counter()
            self._local.total = self.thread_seconds() + now - self._local.started
            with self._lock:
                self.seconds += now - self._local.started
                self._threads -= 1
                if self._threads == 0:
                    self.wall_seconds += now - self._wall_started

    def thread_seconds(self) -> float:
        """The part of :attr:`seconds` spent by the calling thread."""
        return getattr(self._local, "total", 0.0)


_CLOCK = _KernelClock()


def kernel_seconds(wall: bool = False, *, this_thread: bool = False) -> float:
    """Seconds this process has spent compiling kernels or loading them from the cache:
    summed over threads, with ``wall`` the wall time during which any thread did, with
    ``this_thread`` the calling thread's share. Take the difference around a call to
    leave them out of its timing."""
    if this_thread:
        return _CLOCK.thread_seconds()
    return _CLOCK.wall_seconds if wall else _CLOCK.seconds


def kernel(function: F) -> F:
    """Compile ``function`` with numba (cached, no Python objects), if available.

    Every function so decorated is a *kernel*: it takes arrays, scalars and the
    small bundles of :mod:`scanlines.steps` (named tuples, settings records), trusts
    them and validates nothing; validation happens once, in the public entry points.

    A kernel is compiled once per distinct set of argument types, and numba types a
    module constant passed as an argument as a literal of its own: pass
    ``np.int64(CONSTANT)`` where other callers pass a variable, or the kernel (and all
    it calls) is compiled twice.

    Small scalar helpers are kernels like any other, not inlined by numba
    (``inline="always"`` types a helper again inside every caller: 20 % more compile
    time for the adaptive method, 104 s against 84 s cold, and no measurable speed-up,
    since LLVM inlines the linked helpers anyway).
    """
    if numba is None:  # pragma: no cover
        return function
    return _cached_in_own_folder(numba.njit(cache=True, nogil=True, error_model="numpy"), function)


def scan_kernel(function: F) -> F:
    """A method's per-scan kernel: a :func:`kernel` that numba types inside its one
    caller, the method's stack kernel (:mod:`scanlines.steps.stack`), rather than
    compiling it on its own and linking it in, which costs the adaptive method 8 s more
    on a cold cache (every kernel's machine code is emitted again with its callers')."""
    if numba is None:  # pragma: no cover
        return function
    decorate = numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
    return _cached_in_own_folder(decorate, function)


_DECORATING = threading.Lock()


def _cached_in_own_folder(decorate: Callable[[F], F], function: F) -> F:
    """``decorate(function)`` with its cache in :func:`cache_dir` of its module (numba
    places a function's cache where ``CACHE_DIR`` points when it is decorated)."""
    with _DECORATING:
        numba.config.CACHE_DIR = str(cache_dir(function.__module__))
        try:
            return decorate(function)
        finally:
            numba.config.CACHE_DIR = str(cache_root())
