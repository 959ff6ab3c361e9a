"""The scripts in tools/benchmarks/ run against the package as it is (figures not checked)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow  # the benchmark scripts end to end

BENCHMARKS = Path(__file__).parent.parent / "tools" / "benchmarks"


def run(script: str, *args: str, code: int = 0) -> str:
    done = subprocess.run(
        [sys.executable, str(BENCHMARKS / script), *args],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == code, done.stderr[-2000:]
    return done.stdout


def test_stage_times_runs():
    out = run("stage_times.py", "--repeats", "2")
    assert "whole kernel" in out
    assert "assembly (fits, covariances)" in out


def test_extract_time_runs():
    out = run("extract_time.py", "--scenes", "2", "--repeats", "1")
    assert "us/call" in out


def test_same_features_finds_no_difference_and_names_one(tmp_path):
    recorded = tmp_path / "features.npz"
    run("same_features.py", "record", str(recorded), "-n", "1", "--real", "15")
    out = run("same_features.py", "compare", str(recorded))
    assert out.startswith("0 arrays differ of ")
    with np.load(recorded) as stored:
        data = dict(stored)
    data["iepf:|intel|first"] = data["iepf:|intel|first"] + 1
    np.savez_compressed(recorded, **data)
    out = run("same_features.py", "compare", str(recorded), code=1)
    lines = out.splitlines()
    assert lines[0].startswith("1 arrays differ of ")
    assert lines[1].strip().startswith("iepf:|intel|first: scan intel:0:")


def test_compare_versions_times_two_versions_in_their_own_processes():
    out = run("compare_versions.py", "--other", sys.executable, "-m", "iepf", "--rounds", "1")
    rows = [line.split() for line in out.splitlines()[1:]]
    assert [row[0] for row in rows] == ["iepf/intel", "iepf/freiburg", "iepf/tim571", "iepf/1081"]
    assert all(float(value) > 0 for row in rows for value in row[-3:])
