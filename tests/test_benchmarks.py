"""The scripts in tools/benchmarks/ run against the package as it is (figures not checked)."""

from __future__ import annotations

import pickle
import subprocess
import sys
from pathlib import Path

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
    recorded = tmp_path / "features.pkl"
    run("same_features.py", "record", str(recorded), "-n", "1", "--real", "2")
    out = run("same_features.py", "compare", str(recorded))
    assert out.startswith("0 differences in 8 scans x 10 configurations")
    data = pickle.loads(recorded.read_bytes())
    first, *rest = data["features"][("iepf", None)]["intel:1"]
    data["features"][("iepf", None)]["intel:1"] = (first + 1, *rest)
    recorded.write_bytes(pickle.dumps(data))
    out = run("same_features.py", "compare", str(recorded), code=1)
    assert out.splitlines()[:2] == [
        "1 differences in 8 scans x 10 configurations",
        "   iepf:None intel:1 first",
    ]


def test_compare_versions_times_two_copies_of_the_package():
    source = Path(__file__).parent.parent / "src"
    out = run("compare_versions.py", "--other", str(source), "-m", "iepf", "--rounds", "1")
    rows = [line.split() for line in out.splitlines()[1:]]
    assert [row[0] for row in rows] == ["iepf/intel", "iepf/tim571"]
    assert all(float(value) > 0 for row in rows for value in row[1:])


def test_map_offsets_gives_one_map_at_every_offset_and_refuses_beyond_the_limit():
    out = run("map_offsets.py", "--offsets", "0", "1e7", "2e9")
    rows = [line.split("|")[1:-1] for line in out.splitlines()[2:]]
    assert [row[1].strip() for row in rows] == ["0", "0", "2"]
    assert rows[0][2] == rows[1][2]  # the same lines
    assert float(rows[1][3]) < 1e-6
    assert "beyond the map's limit" in rows[2][6]
