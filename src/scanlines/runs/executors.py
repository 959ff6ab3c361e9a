"""Where a fleet run's tasks run: local processes or a Dask cluster, Ctrl-C the command's."""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import multiprocessing
import sys
from collections.abc import Sequence
from typing import Any

from scanlines.errors import ParameterError


@contextlib.contextmanager
def _interrupts_held() -> Any:
    """While the workers start: every thread started meanwhile (Dask's, among them those
    that start the worker processes) blocks SIGINT as its first act, so that the worker
    processes begin with it blocked (a Ctrl-C sent to the whole process group does not
    reach a worker, whose preload, :func:`dask_setup`, then ignores it); and a SIGINT or
    SIGTERM that arrives meanwhile is held, and handed to the handler it was for once the
    cluster is made, so that the caller can stop the cluster.

    SIGINT is not ignored here (an ignored SIGINT is inherited by the workers too): a
    signal sent to the process goes to any thread that does not block it, and one that went
    to another thread (a progress display's) while it was ignored was lost, and the run
    went on to its end."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []
    wanted = (signal.SIGINT, signal.SIGTERM)
    previous = {signum: signal.signal(signum, lambda signum, _: held.append(signum))
                for signum in wanted}  # fmt: skip
    tracer = threading.gettrace()
    threading.settrace(_blocking_sigint(tracer))
    try:
        yield
    finally:
        threading.settrace(tracer)  # type: ignore[arg-type]
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if held:
            _deliver(held[0], previous[held[0]])


def _blocking_sigint(tracer: Any) -> Any:
    """A trace function for new threads: block SIGINT in the thread (its child processes
    inherit that), then trace on with ``tracer`` (a debugger's, coverage's), if any."""
    import signal

    def first_call(frame: Any, event: str, arg: Any) -> Any:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        sys.settrace(tracer)
        return tracer(frame, event, arg) if tracer is not None else None

    return first_call


def _deliver(signum: int, handler: Any) -> None:
    """Hand a signal held back to ``handler``, the one it arrived for."""
    import signal

    if callable(handler):
        handler(signum, None)  # the command's (or Python's) handler: raises the interrupt
    elif handler == signal.SIG_DFL:
        signal.raise_signal(signum)


def dask_setup(worker: Any) -> None:
    """Dask preload of the workers of the LocalCluster a fleet run starts: SIGINT ignored,
    so that a Ctrl-C (sent to the whole process group) reaches the command alone, which
    stops the cluster; and the workers' own logs (their tornado and distributed loggers)
    kept off the console, where a cluster stopped under them would print tracebacks. A
    task's error still reaches the command, with its log."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in ("distributed", "tornado", "tornado.application"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


class _executor:
    """The executor of ``jobs`` and ``scheduler`` (see :func:`run_fleet`), and its name."""

    def __init__(self, jobs: int, scheduler: str | None) -> None:
        self.jobs, self.scheduler = jobs, scheduler
        self._client = self._cluster = self._pool = None
        self._quieted: list[tuple[logging.Logger, int]] = []

    def __enter__(self) -> tuple[cf.Executor, str]:
        try:
            return self._start()
        except BaseException:  # an interrupt while the cluster starts: stop what started
            self.__exit__()
            raise

    def _start(self) -> tuple[cf.Executor, str]:
        if self.scheduler is None:
            context = multiprocessing.get_context("spawn")
            self._pool = cf.ProcessPoolExecutor(self.jobs, mp_context=context)
            return self._pool, f"{self.jobs} local processes"
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ParameterError(
                "a Dask scheduler needs dask and distributed: "
                'pip install ".[fleet]" in a scanlines checkout'
            ) from None
        # The client's and the scheduler's logs (a tornado traceback when an interrupt
        # closes the cluster under a pending gather) stay off the console while they run;
        # a task's error still reaches the command, with its log.
        self._quieted = _quiet_loggers(("tornado", "tornado.application", "distributed"))
        if self.scheduler == "local":
            # silence_logs: the workers' warnings (a task cancelled on Ctrl-C) stay off
            # the console
            # dashboard_address ":0": a free port (None still binds 8787 and warns when
            # another cluster holds it, dask/distributed#8136)
            with _interrupts_held():  # Ctrl-C is the command's to handle, not the workers'
                self._cluster = LocalCluster(n_workers=self.jobs, threads_per_worker=1,
                                             processes=True, dashboard_address=":0",
                                             silence_logs=logging.ERROR,
                                             preload=["scanlines.runs.fleet"])  # fmt: skip
            self._client = Client(self._cluster)
            engine = f"Dask LocalCluster of {self.jobs} workers"
        else:
            self._client = Client(self.scheduler)
            engine = f"Dask scheduler {self.scheduler}"
        return self._client.get_executor(), engine

    def __exit__(self, *exc: object) -> None:
        try:
            if self._pool is not None:
                self._pool.shutdown(cancel_futures=True)
            if self._client is not None:
                self._client.close()
            if self._cluster is not None:
                self._cluster.close()
        finally:
            for logger, level in self._quieted:
                logger.setLevel(level)


def _quiet_loggers(names: Sequence[str]) -> list[tuple[logging.Logger, int]]:
    """Raise the loggers ``names`` to CRITICAL; their loggers and former levels."""
    quieted = []
    for name in names:
        logger = logging.getLogger(name)
        quieted.append((logger, logger.level))
        logger.setLevel(logging.CRITICAL)
    return quieted
