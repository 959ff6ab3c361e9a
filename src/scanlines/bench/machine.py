"""The machine a time was measured on, as the pages state it.

:func:`machine_info` describes the processor, cores, Python, numpy, BLAS, the compiler
of the compiled core and the
thread-count environment, with the load average before the run; ``bench`` and
``reproduce`` print it next to every time they report.
"""

from __future__ import annotations

import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["cores_busy", "load_average", "machine_info"]


def load_average() -> list[float] | None:
    """The 1, 5 and 15 minute load averages, rounded; ``None`` where there are none."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        return None


def cores_busy(seconds: float = 1.0) -> float | None:
    """Cores kept busy by every process over the next ``seconds`` (from ``/proc/stat``),
    ``None`` where there is no such file. Called while this process sleeps, it is what
    the machine's other tenants use, which a load average that counts this process's own
    work just before cannot tell."""
    before = _cpu_times()
    if before is None:
        return None
    time.sleep(seconds)
    after = _cpu_times()
    if after is None:
        return None
    total, idle = after[0] - before[0], after[1] - before[1]
    cores = os.cpu_count() or 1
    return round(cores * (total - idle) / total, 2) if total > 0 else None


def _cpu_times() -> tuple[int, int] | None:
    """All CPU time and idle time (idle and waiting for I/O) so far, in clock ticks."""
    try:
        fields = Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]
    except OSError:
        return None
    ticks = [int(value) for value in fields[:8]]  # user nice system idle iowait irq softirq steal
    return sum(ticks), ticks[3] + ticks[4]


def machine_info() -> dict[str, Any]:
    """CPU, cores, Python, numpy and BLAS, thread-count environment variables, load."""
    cpu, physical = _cpu_from_proc()
    try:
        usable = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        usable = None
    thread_vars = sorted(
        k
        for k in os.environ
        if k.startswith("OPENBLAS") or k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS")
    )
    return {
        "cpu": cpu or platform.processor() or "unknown",
        "cores_logical": os.cpu_count(),
        "cores_physical": physical,
        "cores_usable": usable,
        "platform": platform.platform(),
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "numpy": np.__version__,
        "core_compiler": _core_compiler(),
        "blas": _blas(),
        "openblas_env": {k: os.environ[k] for k in thread_vars if k.startswith("OPENBLAS")},
        "thread_env": {k: os.environ[k] for k in thread_vars if not k.startswith("OPENBLAS")},
        "loadavg_before": load_average(),
    }


def _cpu_from_proc() -> tuple[str | None, int | None]:
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None, None
    model = None
    cores: set[tuple[str, str]] = set()
    physical_id = core_id = None
    for line in text.splitlines():
        key, _, value = line.partition(":")
        key, value = key.strip(), value.strip()
        if key == "model name" and model is None:
            model = value
        elif key == "physical id":
            physical_id = value
        elif key == "core id":
            core_id = value
        elif not key and physical_id is not None and core_id is not None:
            cores.add((physical_id, core_id))
            physical_id = core_id = None
    if physical_id is not None and core_id is not None:
        cores.add((physical_id, core_id))
    return model, (len(cores) or None)


def _core_compiler() -> str:
    """The compiler that built the compiled core (:mod:`scanlines._core`) at install."""
    from scanlines._core import COMPILER

    return COMPILER


def _blas() -> str | None:
    try:
        config = np.show_config(mode="dicts")
        blas = config["Build Dependencies"]["blas"]
        return f"{blas.get('name', '?')} {blas.get('version', '')}".strip()
    except Exception:  # older numpy, or a layout change: not worth failing the bench
        return None
