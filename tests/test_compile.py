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

pytestmark = pytest.mark.skipif(not COMPILED, reason="numba disabled: nothing compiles")

RUN_COLD = """
import json, sys
from scanlines import Extractor
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.runner import run_log
with open_log(sample("intel")) as reader:
    summary = run_log(reader, Extractor(sys.argv[1]), jobs=2)
print(json.dumps({"compile": summary.compile_seconds, "extract": summary.extract_seconds,
                  "total": summary.total_seconds, "scans": summary.scans}))
"""

#: A method whose own kernels are few (clustering, events and assembly are shared).
CHEAP = "line_regression"


def fresh_cache(tmp_path: Path) -> dict[str, str]:
    return dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))


def test_run_summary_leaves_compilation_out_on_a_cold_cache(tmp_path):
    out = subprocess.run(
        [sys.executable, "-c", RUN_COLD, CHEAP],
        env=fresh_cache(tmp_path), capture_output=True, text=True, check=True, timeout=600,
    )  # fmt: skip
    summary = json.loads(out.stdout)
    assert summary["scans"] == 300
    assert summary["compile"] > 2.0  # compiled here, inside the run
    # 300 scans of 180 beams take milliseconds once compiled; compilation takes seconds.
    assert summary["extract"] < summary["compile"] / 4
    assert summary["total"] < summary["compile"] / 2


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
