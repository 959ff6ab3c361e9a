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


def test_stage_times_runs_or_names_the_build_it_needs():
    from scanlines import _core

    if not hasattr(_core, "adaptive_stage_seconds"):  # a product build: no timing code
        done = subprocess.run(
            [sys.executable, str(BENCHMARKS / "stage_times.py"), "--repeats", "2"],
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert done.returncode == 1
        assert done.stderr.strip().splitlines() == [
            "stage_times.py: this build of scanlines has no stage timing; build one with "
            "-Ccmake.define.SCANLINES_STAGE_TIMES=ON (see this script's docstring)"
        ]
        return
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


def test_map_offsets_gives_one_map_at_every_offset_and_refuses_beyond_the_limit():
    out = run("map_offsets.py", "--offsets", "0", "1e7", "2e9")
    rows = [line.split("|")[1:-1] for line in out.splitlines()[2:]]
    assert [row[1].strip() for row in rows] == ["0", "0", "2"]
    assert rows[0][2] == rows[1][2]  # the same lines
    assert float(rows[1][3]) < 1e-6
    assert "beyond the map's limit" in rows[2][6]


def test_real_table_runs_both_modes_over_the_logs_it_finds(tmp_path):
    # A data folder holding two of the shared logs' places, filled with shipped excerpts.
    data = Path(__file__).parent.parent / "src" / "scanlines" / "data"
    places = {
        "intel_excerpt.clf.gz": "intel-research-lab/original/intel-corrected.log.gz",
        "fr079_excerpt.log.gz": "freiburg-079/original/fr079.log.gz",
    }
    for name, place in places.items():
        (tmp_path / place).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / place).write_bytes((data / name).read_bytes())
    table = tmp_path / "table.md"
    args = ["--scans", "24", "--pairs", "6", "-m", "iepf", "-m", "partition?penalty=30@p30"]
    run("real_table.py", str(tmp_path), *args, "--out", str(table), "--cache", str(tmp_path))
    lines = table.read_text().splitlines()
    rows = [line.split(" | ") for line in lines if line.startswith(("| Intel", "| Freiburg"))]
    assert [(row[0], row[1]) for row in rows] == [
        ("| Intel corrected", "profiled"),
        ("| Intel corrected", "bare"),
        ("| Freiburg 079 raw", "profiled"),
        ("| Freiburg 079 raw", "bare"),
    ]
    for row in rows:
        assert row[3] == "6"  # pairs scored
        for cell in row[4:]:
            strict, coverage, _, fidelity = (float(v) for v in cell.strip(" |").split(" / "))
            assert 0.0 <= strict <= 1.0
            assert 0.5 < coverage <= 1.0
            assert 0.0 < fidelity < 30.0
    assert rows[1][2] == "no profile"
    assert rows[0][2].endswith("% of range")
    assert len(list(tmp_path.glob("*.pkl"))) == 2  # the registered pairs, kept for next time
