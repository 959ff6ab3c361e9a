"""A CSV scan without ``range_max`` reads the SICK no-return code (81.83 m) as no return,
as an NPZ does (the same features from both files, and a note); ``--range-max`` decides
instead, on every command that reads logs."""

from __future__ import annotations

import json
import re
from itertools import islice

import numpy as np
import pytest

from cli_helpers import all_commands, scanlines
from scanlines import Extractor
from scanlines.data import sample
from scanlines.io import open_log

CODE = 81.83


@pytest.fixture(scope="module")
def sick_scan():
    """An Intel scan with two stretches of no return written as the SICK code."""
    scan = list(islice(open_log(sample("intel")), 3))[2]
    ranges = np.array(scan.ranges, dtype=np.float64)
    ranges[20:45] = CODE
    ranges[120:150] = CODE
    return scan, ranges


@pytest.fixture
def files(sick_scan, tmp_path):
    scan, ranges = sick_scan
    npz = tmp_path / "sick.npz"
    np.savez(npz, ranges=ranges, angle_min=scan.angle_min, angle_increment=scan.angle_increment)
    csv = tmp_path / "sick.csv"
    csv.write_text(
        f"# angle_min={scan.angle_min!r} angle_increment={scan.angle_increment!r}\n"
        + ",".join(f"{r:.2f}" for r in ranges)
        + "\n"
    )
    return npz, csv


def features(path, **options):
    reader = open_log(path, **options)
    (scan,) = list(reader)
    return scan, Extractor()(scan), reader.notes


def test_a_csv_reads_the_code_as_no_return_as_an_npz_does(files) -> None:
    npz, csv = files
    from_npz, npz_result, _ = features(npz)
    from_csv, csv_result, notes = features(csv)
    assert not from_csv.valid[np.isclose(from_csv.ranges, CODE)].any()
    np.testing.assert_array_equal(from_csv.valid, from_npz.valid)
    np.testing.assert_array_equal(csv_result.breakpoints, npz_result.breakpoints)
    np.testing.assert_array_equal(csv_result.first, npz_result.first)
    assert max((s.rho for s in csv_result.segments), default=0.0) < 40.0
    (note,) = notes
    assert re.match(r"no range_max given: \d+ beams \(\d+\.\d%\) at exactly 81.83 m", note)


def test_range_max_decides_instead(files) -> None:
    npz, csv = files
    for path in (npz, csv):
        scan, _, notes = features(path, range_max=100.0)
        assert notes == []
        assert scan.valid[np.isclose(scan.ranges, CODE)].all()


def test_a_csv_with_its_range_max_is_untouched(files, tmp_path) -> None:
    _, csv = files
    text = csv.read_text().replace("# angle_min", "# range_max=90 angle_min")
    keyed = tmp_path / "keyed.csv"
    keyed.write_text(text)
    scan, _, notes = features(keyed)
    assert notes == []
    assert scan.range_max == 90.0


def test_the_commands_say_so(files, tmp_path) -> None:
    _, csv = files
    out = scanlines("extract", csv, "--json")
    assert out.returncode == 0, out.stderr
    assert "no range_max given" in json.loads(out.stdout)["notes"][0]
    out = scanlines("run", csv, "--out", tmp_path / "f.jsonl")
    assert out.returncode == 0, out.stderr
    assert "no range_max given" in re.sub(r"\s+", " ", out.stdout)
    out = scanlines("info", csv, "--json")
    assert "no range_max given" in json.loads(out.stdout)["reader"]["notes"][0]
    out = scanlines("extract", csv, "--range-max", "100", "--json")
    assert "notes" not in json.loads(out.stdout)


def test_every_command_that_reads_logs_takes_range_max() -> None:
    commands = all_commands()
    log_readers = {
        name
        for name, command in commands.items()
        for option in command.params
        if option.name in ("log", "logs", "file", "play", "real", "map_log")
    }
    expected = {"info", "run", "calibrate", "plot", "view", "map", "localize", "eval real"}
    assert expected | {"eval map"} <= log_readers
    for name in log_readers:
        assert any(o.opts == ["--range-max"] for o in commands[name].params), name


@pytest.mark.parametrize("command", ["run", "plot", "calibrate", "map", "info"])
def test_range_max_reaches_the_reader(command, tmp_path) -> None:
    """On the Intel excerpt (CARMEN): ``--range-max 3`` makes every farther beam a no
    return, which the command's output shows (fewer returns, or none beyond 3 m)."""
    log = sample("intel")
    words = {
        "run": ["run", log, "--scans", "5", "--out", tmp_path / "f.jsonl"],
        "plot": ["plot", log, "--scan", "0", "-o", tmp_path / "p.png"],
        "calibrate": ["calibrate", log, "--scans", "60", "--out", tmp_path / "p.json"],
        "map": ["map", log, "--scans", "30", "--out", tmp_path / "m.json"],
        "info": ["info", log, "--json"],
    }[command]
    out = scanlines(*words, "--range-max", "3")
    assert out.returncode == 0, out.stderr
    if command == "info":
        assert json.loads(out.stdout)["range_max"] <= 3.0
    if command == "run":
        records = [json.loads(line) for line in (tmp_path / "f.jsonl").read_text().splitlines()]
        assert max(s["rho"] for r in records for s in r["segments"]) <= 3.0
    if command == "calibrate":
        assert json.loads((tmp_path / "p.json").read_text())["range_max"] <= 3.0
