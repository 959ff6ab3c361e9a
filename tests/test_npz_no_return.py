"""An NPZ without ``range_max`` whose largest range is a no-return code (the SICK LMS's
81.83 m): every path that reads it (``extract``, ``run``, the library, the viewer) reads
those beams as no return, never as walls 82 m away, and every command that reads NPZ
says so in its help."""

from __future__ import annotations

import json
import re
from itertools import islice
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import scanlines
from scanlines import Extractor, extract
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.scan import valid_returns

CODE = 81.83
#: Farther than anything in the Intel excerpt: a segment there stands on the code.
FAR = 40.0


def sick_ranges(scan) -> np.ndarray:
    """An Intel scan with two stretches of no return written as the SICK code."""
    ranges = np.array(scan.ranges, dtype=np.float64)
    ranges[20:45] = CODE
    ranges[120:150] = CODE
    return ranges


@pytest.fixture(scope="module")
def intel_scans():
    return list(islice(open_log(sample("intel")), 3))


@pytest.fixture(scope="module", params=["float64", "float32"])
def one_scan(request, intel_scans, tmp_path_factory) -> Path:
    """A single-scan NPZ (``ranges`` of shape N) without ``range_max``."""
    scan = intel_scans[2]
    path = tmp_path_factory.mktemp("npz") / f"sick_{request.param}.npz"
    np.savez(path, ranges=sick_ranges(scan).astype(request.param), angle_min=scan.angle_min,
             angle_increment=scan.angle_increment)  # fmt: skip
    return path


@pytest.fixture(scope="module")
def stack(intel_scans, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("npz") / "sick_stack.npz"
    np.savez(path, ranges=np.array([sick_ranges(s) for s in intel_scans]),
             angle_min=intel_scans[0].angle_min,
             angle_increment=intel_scans[0].angle_increment)  # fmt: skip
    return path


def farthest(rhos) -> float:
    return max(rhos, default=0.0)


def test_the_library_reads_the_code_as_no_return(one_scan) -> None:
    reader = open_log(one_scan)
    (scan,) = list(reader)
    assert reader.no_return_code == pytest.approx(CODE)
    assert "no range_max key" in reader.notes[0]
    at_code = np.isclose(scan.ranges, CODE)
    assert at_code.sum() >= 55  # the two stretches, and the log's own
    assert not scan.valid[at_code].any()
    assert scan.valid[~at_code].any()
    # what extraction takes as returns (float32 ranges and limits) is the scan's own mask
    extracted = valid_returns(
        scan.ranges.astype(np.float32), np.float32(scan.range_min), np.float32(scan.range_max)
    )
    np.testing.assert_array_equal(extracted, scan.valid)
    result = extract(scan)
    assert len(result) > 3
    assert farthest(s.rho for s in result.segments) < FAR


def test_extract_reads_the_code_as_no_return_and_says_so(one_scan) -> None:
    out = scanlines("extract", one_scan, "--json")
    assert out.returncode == 0, out.stderr
    payload = json.loads(out.stdout)
    assert payload["segments"]
    assert farthest(s["rho"] for s in payload["segments"]) < FAR
    assert "no range_max key" in payload["notes"][0]
    out = scanlines("extract", one_scan)
    assert out.returncode == 0, out.stderr
    assert re.search(r"note: no range_max key: \d+ beams", re.sub(r"\s+", " ", out.stdout))


def test_run_and_batch_read_the_code_as_no_return(stack, tmp_path) -> None:
    scans = list(open_log(stack))
    table = Extractor().batch(
        np.stack([s.ranges for s in scans]),
        angle_min=scans[0].angle_min,
        angle_increment=scans[0].angle_increment,
        range_max=scans[0].range_max,
    )
    assert len(table.first) > 0
    assert farthest(table.lines[:, 0]) < FAR
    out = scanlines("run", stack, "--out", tmp_path / "f.jsonl")
    assert out.returncode == 0, out.stderr
    records = [json.loads(line) for line in (tmp_path / "f.jsonl").read_text().splitlines()]
    assert len(records) == 3
    assert farthest(s["rho"] for r in records for s in r["segments"]) < FAR


def test_the_viewer_reads_the_code_as_no_return(one_scan) -> None:
    from scanlines.viewer import ScanStore, ViewerSession

    with ScanStore(one_scan) as store:
        assert store.wait_for(2, 60) is False  # one scan, then the end
        session = ViewerSession(store)
        frame = session.frame(0, [{"method": "adaptive"}])
        (result,) = frame["results"]
        assert result["segments"]
        assert farthest(s["rho"] for s in result["segments"]) < FAR
        scan = store.scan(0)
        assert frame["returns"] == int(scan.valid.sum()) == int((scan.ranges < FAR).sum())
        assert "no range_max key" in session.log()["reader"]["notes"][0]


COMMANDS_READING_NPZ = [
    "extract", "info", "run", "calibrate", "plot", "view", "eval real", "eval map", "ros2"
]  # fmt: skip


@pytest.mark.parametrize("command", [*COMMANDS_READING_NPZ, "map"])
def test_every_command_reading_npz_says_how_it_reads_no_range_max(command) -> None:
    out = scanlines(*command.split(), "--help", columns=200)
    assert out.returncode == 0, out.stderr
    text = re.sub(r"[\s│]+", " ", out.stdout)
    assert "without range_max" in text, text
    assert "no-return code (the SICK 81.83 m)" in text, text
