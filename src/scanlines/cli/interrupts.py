"""Ctrl-C and SIGTERM that stop a command cleanly.

The command line installs :func:`handle_signals`: SIGINT and SIGTERM raise
:class:`KeyboardInterrupt` and :class:`Terminated` in the main thread, which unwind
normally, so every writer deletes its temporary output. A compiled kernel call (which
releases the GIL) finishes first: Python runs the handler when the call returns, a
fraction of a second at most. A library user's own signal handling is left alone.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from types import FrameType

__all__ = ["Terminated", "any_terminated", "handle_signals", "ignore_signals", "is_interrupt"]


class Terminated(BaseException):
    """Raised by SIGTERM while :func:`handle_signals` is installed."""


def _on_signal(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt() if signum == signal.SIGINT else Terminated()


def handle_signals() -> None:
    """From now on (main thread only), SIGINT raises :class:`KeyboardInterrupt` and SIGTERM
    :class:`Terminated`."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _on_signal)


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
    """True for an interrupt, also one raised while another exception was handled."""
    return any(isinstance(e, KeyboardInterrupt | Terminated) for e in _chain(error))


def any_terminated(error: BaseException) -> bool:
    """True when SIGTERM (not Ctrl-C) is behind ``error``."""
    return any(isinstance(e, Terminated) for e in _chain(error))
