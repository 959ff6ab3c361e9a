"""A file that is not there is said the same way by every command, whatever the file is
(a log of any format, a single scan, a configuration, a sensor profile, a scene set):
``scanlines: error: PATH: no such file or directory``, one line, exit code 2."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from cli_helpers import scanlines
from scanlines.data import sample

INTEL = sample("intel")
#: The wording (``scanlines.errors.NO_SUCH_FILE``).
NO_SUCH_FILE = "no such file or directory"

#: name -> (arguments, the missing file) with ``{missing}`` and ``{tmp}`` to fill in.
CASES = {
    "info": (["info", "{missing}/x.clf"], "x.clf"),
    "info bag": (["info", "{missing}/x.bag"], "x.bag"),
    "info mcap": (["info", "{missing}/x.mcap"], "x.mcap"),
    "extract npz": (["extract", "{missing}/x.npz"], "x.npz"),
    "extract csv": (
        ["extract", "{missing}/x.csv", "--angle-min", "0", "--angle-increment", "1"],
        "x.csv",
    ),
    "extract --config": (["extract", "{scan}", "--config", "{missing}/c.toml"], "c.toml"),
    "extract --sensor-profile": (
        ["extract", "{scan}", "--sensor-profile", "{missing}/p.json"],
        "p.json",
    ),
    "run": (["run", "{missing}/x.clf"], "x.clf"),
    "run --out": (["run", "{missing}/x.dat", "--out", "{tmp}/f.jsonl"], "x.dat"),
    "run --config": (["run", INTEL, "--config", "{missing}/c.toml"], "c.toml"),
    "run --sensor-profile": (
        ["run", INTEL, "--sensor-profile", "{missing}/p.json", "--scans", "0:2"],
        "p.json",
    ),
    "calibrate": (["calibrate", "{missing}/x.clf"], "x.clf"),
    "plot": (["plot", "{missing}/x.clf", "--scan", "0", "-o", "{tmp}/p.png"], "x.clf"),
    "plot --config": (["plot", INTEL, "--scan", "0", "--config", "{missing}/c.toml"], "c.toml"),
    "view": (["view", "{missing}/x.clf", "--no-browser"], "x.clf"),
    "eval real": (["eval", "real", "{missing}/x.clf", "--out", "{tmp}/e"], "x.clf"),
    "eval sim --scenes": (
        ["eval", "sim", "--scenes", "{missing}/s.npz", "--out", "{tmp}/e"],
        "s.npz",
    ),
    "eval sim --config": (
        ["eval", "sim", "--config", "{missing}/c.toml", "--out", "{tmp}/e"],
        "c.toml",
    ),
    "map": (["map", "{missing}/x.clf", "--out", "{tmp}/m.geojson"], "x.clf"),
    "ros2 --play": (["ros2", "--play", "{missing}/x.clf", "--wait", "30"], "x.clf"),
}


@pytest.fixture(scope="module")
def one_scan(tmp_path_factory) -> Path:
    import numpy as np

    path = tmp_path_factory.mktemp("scan") / "scan.npz"
    np.savez(path, ranges=np.full(90, 2.0), angle_min=0.0, angle_increment=0.01, range_max=30.0)
    return path


@pytest.mark.parametrize("case", list(CASES))
def test_a_missing_file_is_said_the_same_way(case, tmp_path, one_scan) -> None:
    if case == "ros2 --play" and importlib.util.find_spec("cyclonedds") is None:
        pytest.skip("scanlines ros2 needs Cyclone DDS")
    args, name = CASES[case]
    missing = tmp_path / "nowhere"
    filled = [
        str(a).format(missing=missing, tmp=tmp_path, scan=one_scan) if isinstance(a, str) else a
        for a in args
    ]
    out = scanlines(*filled)
    assert out.returncode == 2, out.stderr
    assert out.stderr.strip().splitlines() == [
        f"scanlines: error: {missing / name}: {NO_SUCH_FILE}"
    ], out.stderr


def test_several_logs_name_each_missing_one_the_same_way(tmp_path) -> None:
    missing = tmp_path / "nowhere" / "x.clf"
    (tmp_path / "out").mkdir()
    out = scanlines("run", INTEL, missing, "--scans", "0:2", "--out", tmp_path / "out")
    assert out.returncode == 2, out.stderr
    assert out.stderr.strip().splitlines()[-1].endswith(f"{missing}: {NO_SUCH_FILE}")
