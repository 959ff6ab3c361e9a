"""Watching kernel compilation without importing numba.

A command shows compilation from its start (:func:`watch_compilation`), but importing
numba takes most of a second, which a command that needs no kernel yet (``scanlines
view`` serving its page) should not wait for. So the watchers are kept here, and
:mod:`scanlines._jit` forwards numba's compile events to them once numba is loaded.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from contextlib import contextmanager

__all__ = ["compile_ended", "compile_started", "watch_compilation"]


class _Watcher:
    def __init__(self, on_compile: Callable[[str], None], on_done: Callable[[], None]) -> None:
        self.on_compile, self.on_done = on_compile, on_done
        self.depth = 0


_WATCHERS: list[_Watcher] = []
_LOCK = threading.Lock()


@contextmanager
def watch_compilation(on_compile: Callable[[str], None], on_done: Callable[[], None]):
    """Call ``on_compile(name)`` whenever a kernel starts compiling (not on cache loads),
    and ``on_done()`` when the outermost compilation in progress ends."""
    watcher = _Watcher(on_compile, on_done)
    with _LOCK:
        _WATCHERS.append(watcher)
    try:
        yield
    finally:
        with _LOCK:
            _WATCHERS.remove(watcher)


def compile_started(name: str) -> None:
    """A kernel named ``name`` starts compiling (called by :mod:`scanlines._jit`)."""
    for watcher in list(_WATCHERS):
        watcher.depth += 1
        watcher.on_compile(name)


def compile_ended() -> None:
    """The kernel that started compiling last is compiled."""
    for watcher in list(_WATCHERS):
        watcher.depth -= 1
        if watcher.depth == 0:
            watcher.on_done()
