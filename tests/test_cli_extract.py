"""``scanlines extract`` end to end: outputs, figure, exit codes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cli_helpers import Ran, scanlines
from scenes import scan_of, square_room


def run(*args: str) -> Ran:
    return scanlines(*args)


@pytest.fixture(scope="module")
def room_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("extract")
    scan = scan_of(square_room(), fov_deg=340, step_deg=1 / 3, sigma=0.01, seed=0, start_deg=-170)
    csv = folder / "room.csv"
    csv.write_text(" ".join(f"{r:.5f}" for r in scan.ranges) + "\n")
    npz = folder / "room.npz"
    np.savez(
        npz, ranges=scan.ranges, angle_min=scan.angle_min, angle_increment=scan.angle_increment
    )
    return csv, npz


def test_json_output_from_npz(room_files):
    _, npz = room_files
    out = run("extract", str(npz), "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert len(data["segments"]) == 5
    assert len(data["corners"]) == 4
    assert data["breakpoints"] == []


def test_csv_with_degrees_table_and_plot(room_files, tmp_path):
    csv, _ = room_files
    figure = tmp_path / "room.png"
    out = run(
        "extract",
        str(csv),
        "--angle-min",
        "-170",
        "--angle-increment",
        str(1 / 3),
        "--plot",
        str(figure),
        "--param",
        "k=3",
    )
    assert out.returncode == 0, out.stderr
    assert "corners (4)" in out.stdout
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_paper_preset_from_the_command_line(room_files):
    _, npz = room_files
    out = run("extract", str(npz), "--preset", "paper", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["params"]["criterion"] == "sse"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.csv", "--angle-min", "0", "--angle-increment", "1"], "missing.csv"),
        (["{npz}", "--param", "nonsense=1"], "nonsense"),
        (["{npz}", "--param", "k"], "NAME=VALUE"),
        (["{npz}", "--method", "magic"], "magic"),
        (["{csv}"], "angle_min"),
        (["{bad}", "--angle-min", "0", "--angle-increment", "1"], "bad.csv"),
    ],
)
def test_bad_input_exits_2_with_one_line(room_files, tmp_path, args, message):
    csv, npz = room_files
    bad = tmp_path / "bad.csv"
    bad.write_text("1.0, 2.0, oops, 3.0\n")
    args = [a.format(npz=npz, csv=csv, bad=bad) for a in args]
    out = run("extract", *args)
    assert out.returncode == 2
    assert message in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
    assert "Traceback" not in out.stderr


def test_angles_in_degrees_are_converted(room_files):
    csv, _ = room_files
    out = run("extract", str(csv), "--angle-min", "-170", "--angle-increment", str(1 / 3), "--json")
    data = json.loads(out.stdout)
    alphas = sorted(round(math.degrees(s["alpha"])) % 360 for s in data["segments"])
    assert alphas == [0, 90, 180, 180, 270]
