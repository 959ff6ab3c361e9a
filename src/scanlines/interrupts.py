"""Ctrl-C and SIGTERM that stop a command cleanly, never from inside a compiled kernel.

Python runs a signal handler between bytecodes, wherever the main thread is. If that is
inside numba's dispatcher (which runs some Python while it picks the compiled code), the
``KeyboardInterrupt`` is lost there and resurfaces as ``SystemError: CPUDispatcher(...)
returned a result with an exception set``. So the command line installs
:func:`handle_signals`: SIGINT and SIGTERM raise :class:`KeyboardInterrupt` and
:class:`Terminated` as usual, except while the main thread is inside :data:`kernel_calls`
(the extractor's kernel calls, and the command line's imports), where the signal waits
until the call returns (a fraction of a second; a kernel being compiled is interrupted at
once, compiling being Python). Either way the exception unwinds normally, so every
writer deletes its temporary output.

A library user's own signal handling is left alone: :data:`kernel_calls` only defers
signals while :func:`handle_signals` is installed.
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType, TracebackType

__all__ = ["Terminated", "any_terminated", "handle_signals", "is_interrupt", "kernel_calls"]


class Terminated(BaseException):
    """Raised by SIGTERM while :func:`handle_signals` is installed."""


class _KernelCalls:
    """A context around kernel calls in which the installed handlers defer signals."""

    def __init__(self) -> None:
        self.depth = 0
        self.compiling = 0
        self.pending: int | None = None
        self.main_thread = threading.main_thread().ident
        self._listening = False

    def __enter__(self) -> None:
        if threading.get_ident() == self.main_thread:
            self.depth += 1
            if not self._listening:
                self._listen_to_compilation()

    def _listen_to_compilation(self) -> None:
        """Count numba's compilations: a compilation is Python code, interrupted at once
        (a cold compile takes a minute; the signal does not wait for it)."""
        numba = sys.modules.get("numba")
        if numba is None:
            return
        import numba.core.event as events

        calls = self

        class Compiling(events.Listener):
            def on_start(self, event: object) -> None:
                if threading.get_ident() == calls.main_thread:
                    calls.compiling += 1

            def on_end(self, event: object) -> None:
                if threading.get_ident() == calls.main_thread:
                    calls.compiling -= 1

        events.register("numba:compile", Compiling())
        self._listening = True

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if threading.get_ident() != self.main_thread:
            return
        self.depth -= 1
        if self.depth == 0 and self.pending is not None:
            signum, self.pending = self.pending, None
            raise _exception_for(signum)

    def on_signal(self, signum: int, frame: FrameType | None) -> None:
        if self.depth > 0 and self.compiling == 0:
            self.pending = signum
            return
        raise _exception_for(signum)


#: Wrap calls into compiled kernels: ``with kernel_calls: ...``.
kernel_calls = _KernelCalls()


def _exception_for(signum: int) -> BaseException:
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated()


def handle_signals() -> None:
    """From now on (main thread only), SIGINT raises :class:`KeyboardInterrupt` and SIGTERM
    :class:`Terminated`, both held back while a kernel call runs."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, kernel_calls.on_signal)


def ignore_signals() -> None:
    """Ignore SIGINT and SIGTERM: the work is done and the process is exiting (a signal
    now would only turn a complete run into a failed one)."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)


def _chain(error: BaseException | None) -> Iterator[BaseException]:
    for _ in range(10):
        if error is None:
            return
        yield error
        error = error.__cause__ or (None if error.__suppress_context__ else error.__context__)


def is_interrupt(error: BaseException) -> bool:
    """True for an interrupt, including one numba wrapped in a ``SystemError``."""
    return any(isinstance(e, KeyboardInterrupt | Terminated) for e in _chain(error))


def any_terminated(error: BaseException) -> bool:
    """True when SIGTERM (not Ctrl-C) is behind ``error``."""
    return any(isinstance(e, Terminated) for e in _chain(error))
