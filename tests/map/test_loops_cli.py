"""``scanlines map --align`` closes loops: the closures in the summary, metadata and plot."""

from __future__ import annotations

import json
import subprocess
import sys

from cli_helpers import scanlines
from scanlines.data import sample


def test_map_align_lists_its_closures(tmp_path):
    ran = scanlines(
        "map", sample("intel"), "--out", tmp_path / "m.json", "--align",
        "--poses-out", tmp_path / "p.tum", "--plot", tmp_path / "m.png",
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    assert "closures accepted of" in ran.stdout
    meta = json.loads((tmp_path / "m.json").read_text())
    loops = meta["loops"]
    assert loops["accepted"] == len(loops["closures"])
    assert loops["accepted"] + sum(loops["refused"].values()) == loops["candidates"]
    assert loops["solver"]["poses"] == 300
    for closure in loops["closures"]:
        assert closure["scan_i"] < closure["scan_j"]
        assert closure["inliers"] >= loops["settings"]["min_inliers"]
    assert "loops closed" in meta["poses"]
    assert (tmp_path / "m.png").stat().st_size > 0


def test_no_loops_leaves_the_tracked_map(tmp_path):
    ran = scanlines("map", sample("intel"), "--out", tmp_path / "m.json", "--align", "--no-loops")
    assert ran.returncode == 0, ran.stderr
    assert "loops" not in json.loads((tmp_path / "m.json").read_text())
    assert "closures accepted" not in ran.stdout


def test_without_scipy_one_line_says_so(tmp_path):
    code = (
        "import sys; sys.modules['scipy'] = None; from scanlines.cli import main; "
        f"sys.argv = ['scanlines', 'map', {str(sample('intel'))!r}, '--out', "
        f"{str(tmp_path / 'm.json')!r}, '--align', '--scans', '40']; main()"
    )
    ran = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert ran.returncode == 0, ran.stderr
    said = [line for line in ran.stderr.splitlines() if "scipy" in line]
    assert said == [
        "loops not closed: closing them needs scipy (pip install 'scanlines[map]'); the map "
        "is built from the tracked poses"
    ]


def test_eval_map_align_closes_the_loops(tmp_path):
    ran = scanlines(
        "eval", "map", sample("intel"), "--align", "--scans", "120", "--out", tmp_path
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    payload = json.loads((tmp_path / "map_eval.json").read_text())
    assert "loops closed" in payload["poses"]
