"""Compilation: ``scanlines compile``, what the user sees while kernels compile, and run
summaries that leave compilation out. Each test starts a process with an empty cache."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from scanlines._jit import COMPILED

pytestmark = [
    pytest.mark.slow,  # cold compiles
    pytest.mark.skipif(not COMPILED, reason="numba disabled: nothing compiles"),
]

COLD_PROCESS = """
import json, sys
import numpy as np
from numba.core.registry import CPUDispatcher
from scanlines import Extractor, Scan
from scanlines.builtin_methods import BUILTIN_METHODS
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.runner import log_profile, run_log

with open_log(sample("intel")) as reader:  # first: a run that compiles inside it
    summary = run_log(reader, Extractor(sys.argv[1]), jobs=2)
print(json.dumps({"compile": summary.compile_seconds, "extract": summary.extract_seconds,
                  "total": summary.total_seconds, "scans": summary.scans}))
with open_log(sample("intel")) as reader:  # then every method, every kind of input
    scans = [scan for _, scan in zip(range(12), reader)]
as_float32 = [Scan(s.ranges.astype(np.float32), s.angle_min, s.angle_increment,
                   s.range_min, s.range_max) for s in scans]
profile = log_profile(sample("intel"), {})
ranges = np.stack([s.ranges for s in scans[:4]])
for method in BUILTIN_METHODS:
    for options, inputs in (({}, scans), ({"sensor_profile": profile}, scans), ({}, as_float32)):
        extractor = Extractor(method, **options)
        for scan in inputs:
            extractor(scan)
        extractor.batch(ranges, scans[0].angle_min, scans[0].angle_increment)
for name, module in list(sys.modules.items()):
    if name.startswith("scanlines"):
        for attribute, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.__module__ == name:
                if len(value.signatures) > 1 and attribute not in sys.argv[2:]:
                    print(f"{name}.{attribute}: {value.signatures}")
"""

#: Kernels meant for several argument types (one signature per array dtype).
GENERIC_KERNELS = ("room_for",)

#: A method whose own kernels are few (clustering, events and assembly are shared).
CHEAP = "line_regression"


def fresh_cache(tmp_path: Path) -> dict[str, str]:
    return dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def cold_process(tmp_path_factory) -> list[str]:
    """One process from an empty cache: a run, then every method (:data:`COLD_PROCESS`)."""
    folder = tmp_path_factory.mktemp("cold")
    done = subprocess.run(
        [sys.executable, "-c", COLD_PROCESS, CHEAP, *GENERIC_KERNELS],
        env=fresh_cache(folder), capture_output=True, text=True, timeout=1800,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout.splitlines()


def test_run_summary_leaves_compilation_out_on_a_cold_cache(cold_process):
    summary = json.loads(cold_process[0])
    assert summary["scans"] == 300
    assert summary["compile"] > 2.0  # compiled here, inside the run
    # 300 scans of 180 beams take milliseconds once compiled; compilation takes seconds.
    assert summary["extract"] < summary["compile"] / 4
    assert summary["total"] < summary["compile"] / 2


def test_every_kernel_holds_one_signature_after_every_method_ran(cold_process):
    """Production passes one type per argument (float32 ranges and profiles included):
    a second signature is a second compile of that kernel and all it calls. From an
    empty cache, since a kernel called inside another is typed (and specialised, a
    literal ``True`` or ``0`` as a type of its own) only when its caller compiles."""
    assert cold_process[1:] == []


def test_compile_command_fills_the_cache_and_later_processes_only_load(tmp_path):
    env = fresh_cache(tmp_path)
    out = subprocess.run(
        [sys.executable, "-m", "scanlines", "compile", "--method", CHEAP, "--jobs", "1"],
        env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert f"{CHEAP}: " in out.stderr
    assert "kernels ready in" in out.stdout
    assert list((tmp_path / "cache").rglob("*.nbi"))
    load = (
        "from scanlines import Extractor; from scanlines._jit import kernel_seconds; "
        f"Extractor({CHEAP!r}).warm_up(); print(kernel_seconds())"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", load], env=env, capture_output=True, text=True, check=True
    )
    assert float(loaded.stdout) < 2.0  # loading, not compiling


def test_compile_refuses_an_unknown_method(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "scanlines", "compile", "--method", "nope"],
        env=fresh_cache(tmp_path), capture_output=True, text=True,
    )  # fmt: skip
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1
    assert "nope" in out.stderr


def test_a_command_that_compiles_says_so_on_stderr(tmp_path):
    scan = tmp_path / "scan.csv"
    scan.write_text(",".join(["2.0"] * 90 + ["3.0"] * 91) + "\n")
    out = subprocess.run(
        [sys.executable, "-m", "scanlines", "extract", str(scan), "--method", CHEAP,
         "--angle-min", "-90", "--angle-increment", "1"],
        env=fresh_cache(tmp_path), capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert out.stderr.count("compiling kernels for first use") == 1
    assert out.stderr.count("scanlines: compiled ") == 1


def test_the_stages_of_adaptive_are_captured_in_plain_python(tmp_path):
    """The second core compiles the stages with the arguments of a plain-Python run: every
    stage named must be called by the method, in the order named."""
    import pickle

    from scanlines.methods.adaptive import Adaptive

    path = tmp_path / "arguments.pickle"
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    subprocess.run(
        [sys.executable, "-m", "scanlines.warm", "capture", "adaptive", str(path)],
        env=env, check=True, timeout=300,
    )  # fmt: skip
    calls = pickle.loads(path.read_bytes())
    assert [name for name, _ in calls] == list(Adaptive.stages)


def test_no_helper_process_when_the_stages_are_cached():
    from scanlines import Extractor
    from scanlines.warm import start_stage_compiler

    Extractor().warm_up()  # this session's cache now holds every stage
    assert start_stage_compiler("adaptive") is None
    assert start_stage_compiler("iepf") is None  # no stages named
