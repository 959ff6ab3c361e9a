"""Compiling the kernels sooner: ahead of time (``scanlines compile``), and on two cores.

A kernel is compiled on its first use and cached on disk (:mod:`scanlines._jit`); a
container image or a CI cache that runs :func:`compile_kernels` once starts every later
process at once. Methods are spread over worker processes, each compiling into the
shared cache (a kernel two methods share may be compiled by both, at the same time).

One method's kernel is compiled top-down by numba, one callee after another. A method
that names its ``stages`` (the kernels its own kernel calls, in order) can be compiled
from both ends at once: :func:`start_stage_compiler` starts a process that compiles the
stages last to first into the cache, while this process compiles the method's kernel
first to last and loads from the cache what the other process has finished. The stages'
arguments come from one run of the method in plain Python (``NUMBA_DISABLE_JIT``) on the
warm-up scan, so they have the types the method's kernel gives them.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.extractor import Extractor, _warm_up_scan, method_names
from scanlines.methods import method_class
from scanlines.scan import Scan

__all__ = [
    "compile_kernels",
    "compiling_from_both_ends",
    "start_stage_compiler",
    "stop",
    "warm_method",
]

PROFILE = "sensor profile"
"""The name under which the kernels of :func:`~scanlines.sensor_profile.estimate_profile`
are warmed."""

TEXT_LOGS = "text logs"
"""The name under which the number reader of the text logs
(:func:`~scanlines.io.numbers.number_fields`) is warmed."""


def warm_method(name: str) -> tuple[str, float]:
    """Compile (or load) the kernels ``name`` uses; returns ``(name, seconds)``.

    ``name`` is a method, :data:`PROFILE` for the sensor-profile estimate, or
    :data:`TEXT_LOGS` for the text logs' number reader."""
    started = time.perf_counter()
    if name == TEXT_LOGS:
        from scanlines.io.numbers import number_fields

        number_fields("FLASER 1 2.5 host")
    elif name == PROFILE:
        from scanlines.sensor_profile import ProfileError, estimate_profile

        with contextlib.suppress(ProfileError):  # the scans are made to be measurable
            estimate_profile(_noisy_scans())
    else:
        with compiling_from_both_ends(name):
            Extractor(name).warm_up()
    return name, time.perf_counter() - started


def compile_kernels(
    methods: Sequence[str] | None = None,
    jobs: int = 1,
    on_done: Callable[[str, float], None] = lambda _name, _seconds: None,
) -> dict[str, float]:
    """Compile the kernels of ``methods`` (default: every method, the sensor-profile
    estimate and the text logs' number reader) in ``jobs`` processes; returns the seconds
    each took, in the order done."""
    names = [*(methods or method_names())]
    if methods is None:
        names += [PROFILE, TEXT_LOGS]
    for name in names:
        if name not in (PROFILE, TEXT_LOGS):
            Extractor(name)  # an unknown method fails here, before any process starts
    seconds: dict[str, float] = {}
    if jobs == 1 or len(names) == 1:
        for name in names:
            seconds[name] = warm_method(name)[1]
            on_done(name, seconds[name])
        return seconds
    with ProcessPoolExecutor(min(jobs, len(names))) as pool:
        for future in as_completed([pool.submit(warm_method, name) for name in names]):
            name, took = future.result()
            seconds[name] = took
            on_done(name, took)
    return seconds


def start_stage_compiler(method: str) -> subprocess.Popen | None:
    """A process compiling ``method``'s stages last to first (the module docstring), or
    ``None`` when there is nothing to gain: no stages, a single core, numba disabled, or
    the stages already cached. Pass the result to :func:`stop` once this process has
    compiled the method (what the other process has not finished by then is not needed)."""
    from scanlines._jit import COMPILED
    from scanlines.runner import default_jobs

    stages = getattr(method_class(method), "stages", ())
    if not (COMPILED and stages and default_jobs() > 1):
        return None
    module = sys.modules[method_class(method).__module__]
    if all(_cached(getattr(module, stage)) for stage in stages):
        return None
    command = [sys.executable, "-m", "scanlines.warm", "stages", method]
    return subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


@contextmanager
def compiling_from_both_ends(method: str) -> Iterator[None]:
    """A block in which a second process compiles ``method``'s stages (when that helps:
    :func:`start_stage_compiler`); warm the method up inside it."""
    helper = start_stage_compiler(method)
    try:
        yield
    finally:
        stop(helper)


def stop(helper: subprocess.Popen | None) -> None:
    """End a process of :func:`start_stage_compiler` (numba writes each cache entry
    atomically, so an interrupted compilation leaves nothing half-written)."""
    if helper is not None and helper.poll() is None:
        helper.terminate()
        helper.wait(timeout=30)


def _cached(dispatcher: Any) -> bool:
    """Whether a compiled kernel has an entry in the cache of its module."""
    from scanlines._jit import cache_dir

    function = dispatcher.py_func
    return any(cache_dir(function.__module__).rglob(f"*.{function.__name__}-*.nbi"))


def _compile_stages(method: str) -> None:
    """Compile ``method``'s stages, last to first, with the arguments of a plain-Python
    run (captured in a child process: numba is disabled there)."""
    module = sys.modules[method_class(method).__module__]
    with tempfile.TemporaryDirectory(prefix="scanlines-stages-") as folder:
        path = Path(folder) / "arguments.pickle"
        env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
        capture = [sys.executable, "-m", "scanlines.warm", "capture", method, str(path)]
        subprocess.run(capture, env=env, check=True)
        with path.open("rb") as handle:
            calls = pickle.load(handle)  # written just now by our own child
    for name, arguments in reversed(calls):
        getattr(module, name)(*arguments)


def _capture_stage_arguments(method: str, path: str) -> None:
    """Run ``method`` on the warm-up scan in plain Python, keeping the arguments of the
    first call of each stage."""
    module = sys.modules[method_class(method).__module__]
    calls: dict[str, tuple[Any, ...]] = {}

    def recording(name: str, function: Callable) -> Callable:
        def call(*arguments: Any) -> Any:
            calls.setdefault(name, arguments)
            return function(*arguments)

        return call

    for name in method_class(method).stages:
        setattr(module, name, recording(name, getattr(module, name)))
    Extractor(method).warm_up()
    with open(path, "wb") as handle:
        pickle.dump(list(calls.items()), handle)


def _noisy_scans(count: int = 8) -> list[Scan]:
    """The warm-up room with 5 mm range noise, a few scans (enough to measure)."""
    room = _warm_up_scan()
    rng = np.random.default_rng(0)
    return [
        Scan(
            room.ranges + rng.normal(0.0, 0.005, len(room)) * (room.ranges > 0),
            room.angle_min,
            room.angle_increment,
            range_max=room.range_max,
        )
        for _ in range(count)
    ]


if __name__ == "__main__":  # the helper processes of start_stage_compiler
    if sys.argv[1] == "stages":
        _compile_stages(sys.argv[2])
    elif sys.argv[1] == "capture":
        _capture_stage_arguments(sys.argv[2], sys.argv[3])
