"""The scripts in benchmarks/ run against the package as it is (their figures are not checked)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).parent.parent / "benchmarks"


def run(script: str, *args: str) -> str:
    done = subprocess.run(
        [sys.executable, str(BENCHMARKS / script), *args],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def test_stage_times_runs():
    out = run("stage_times.py", "--repeats", "2")
    assert "whole kernel" in out
    assert "assembly (fits, covariances)" in out


def test_extract_time_runs():
    out = run("extract_time.py", "--scenes", "2", "--repeats", "1")
    assert "us/call" in out


@pytest.mark.parametrize("script", ["compare_versions.py", "same_features.py"])
def test_before_and_after_checks_explain_themselves(script):
    assert "usage:" in run(script, "--help")
