"""``scanlines info``, ``run``, ``plot`` and ``demo`` end to end on shipped and fixture logs."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from cli_helpers import Ran, scanlines
from scanlines.data import sample

FIXTURES = Path(__file__).parent / "io" / "fixtures"


def run(*args: str, cwd: Path | None = None) -> Ran:
    return scanlines(*args, cwd=cwd)


def one_error_line(out: Ran, *needles: str) -> None:
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    for needle in needles:
        assert needle in lines[0]


def test_info_describes_the_intel_sample():
    out = run("info", sample("intel"), "--json")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["format"] == "carmen"
    assert info["scans"] == 300
    assert info["beams"] == {"180": 300}
    assert info["field_of_view_deg"] == [180.0]
    assert info["resolution_deg"] == [1.0]
    assert 0.0 < info["no_return_share"] < 0.2
    assert info["range_max"] < 80.0  # 81.83 "no return" codes are not ranges
    assert info["with_pose"] == 300


def test_info_table_mentions_skipped_lines():
    out = run("info", sample("freiburg"))
    assert out.returncode == 0, out.stderr
    assert "ODOM" in out.stdout
    assert "PARAM" in out.stdout


def test_run_writes_one_json_object_per_scan_and_meta(tmp_path):
    target = tmp_path / "features.jsonl"
    out = run("run", sample("freiburg"), "--scans", "10:20", "--out", target, "--param", "k=3")
    assert out.returncode == 0, out.stderr
    records = [json.loads(line) for line in target.read_text().splitlines()]
    assert [r["scan"] for r in records] == list(range(10, 20))
    assert set(records[0]) == {
        "scan",
        "timestamp",
        "pose",
        "segments",
        "breakpoints",
        "corners",
        "breakpoint_xy",
        "corner_xy",
    }
    assert len(records[0]["corner_xy"]) == len(records[0]["corners"])
    meta = json.loads((tmp_path / "features.jsonl.meta.json").read_text())
    assert meta["method"] == "adaptive"
    assert meta["params"]["k"] == 3.0
    assert meta["counts"]["scans"] == 10
    assert "segments / scan" in out.stdout


def test_run_csv_in_world_frame(tmp_path):
    target = tmp_path / "segments.csv"
    out = run("run", sample("intel"), "--scans", "0:5", "--out", target, "--frame", "world")
    assert out.returncode == 0, out.stderr
    with target.open() as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == [
        "scan",
        "timestamp",
        "first",
        "last",
        "start_x",
        "start_y",
        "end_x",
        "end_y",
        "rho",
        "alpha",
        "n_points",
        "rms",
        "var_rho",
        "cov_rho_alpha",
        "var_alpha",
        "start_kind",
        "end_kind",
        "pose_x",
        "pose_y",
        "pose_theta",
        "feature",
        "beam",
        "x",
        "y",
    ]
    assert {int(r[0]) for r in rows[1:]} == set(range(5))


def _quiet_profile(tmp_path):
    """A sensor profile file, so that `run` measures none (and says nothing about it)."""
    from scanlines.sensor.profile import SensorProfile

    return SensorProfile(noise_sigma0=0.01, noise_per_metre=0.0).save(tmp_path / "p.json")


def test_world_frame_without_poses_is_an_input_error(tmp_path):
    log = tmp_path / "scans.csv"
    log.write_text("1.0, 1.0, 1.0, 1.0\n")
    out = run(
        "run",
        log,
        "--angle-min",
        "-10",
        "--angle-increment",
        "5",
        "--frame",
        "world",
        "--out",
        tmp_path / "x.jsonl",
        "--sensor-profile",
        _quiet_profile(tmp_path),
    )
    one_error_line(out, "pose")
    assert not (tmp_path / "x.jsonl").exists()


def test_malformed_record_fails_or_is_skipped(tmp_path):
    bad = FIXTURES / "carmen_not_a_number.log"
    failed = run("run", bad, "--out", tmp_path / "a.jsonl")
    one_error_line(failed, "carmen_not_a_number.log", "line 3", "range[2]")
    assert not (tmp_path / "a.jsonl").exists()
    skipped = run("run", bad, "--on-error", "skip", "--out", tmp_path / "b.jsonl")
    assert skipped.returncode == 0, skipped.stderr
    meta = json.loads((tmp_path / "b.jsonl.meta.json").read_text())
    assert meta["counts"]["skipped_scan_records"] == 1
    assert meta["counts"]["skip_reasons"] == {"range": 1}


@pytest.mark.parametrize(
    ("name", "needle"),
    [("truncated.clf.gz", "truncated"), ("empty.log", "empty"), ("unknown.xyz", "unknown.xyz")],
)
def test_bad_files_exit_2(name, needle):
    out = run("info", FIXTURES / name)
    one_error_line(out, needle)


def test_bad_scan_slice_exits_2():
    one_error_line(run("run", sample("intel"), "--scans", "a:b"), "--scans")


def test_plot_one_scan_and_a_grid(tmp_path):
    single, grid = tmp_path / "one.png", tmp_path / "grid.png"
    assert run("plot", sample("intel"), "--scan", "3", "-o", single).returncode == 0
    out = run("plot", sample("freiburg"), "--scans", "0:300:50", "-o", grid)
    assert out.returncode == 0, out.stderr
    for figure in (single, grid):
        assert figure.read_bytes()[:4] == b"\x89PNG"


def test_demo_writes_features_and_a_figure(tmp_path):
    out = run("demo", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    folder = tmp_path / "scanlines-demo"
    lines = (folder / "intel.jsonl").read_text().splitlines()
    assert len(lines) == 300
    assert (folder / "intel.png").read_bytes()[:4] == b"\x89PNG"
    assert str((folder / "intel.jsonl").resolve()) in out.stdout


@pytest.mark.parametrize(
    ("log", "scans", "counted"),
    [
        (FIXTURES / "intel_every5th_rows1098-1109.npz", None, "12/12"),  # the file says how many
        (sample("intel"), "0:40", "40/40"),  # the selection bounds it
    ],
)
def test_run_shows_percentage_and_time_left_when_the_count_is_known(
    log, scans, counted, monkeypatch
):
    from typer.testing import CliRunner

    from scanlines.cli import app

    monkeypatch.setenv("FORCE_COLOR", "1")  # draw the bar as on a terminal
    selection = ["--scans", scans] if scans else []
    done = CliRunner().invoke(app, ["run", str(log), *selection, "--jobs", "1"])
    assert done.exit_code == 0, done.output
    assert "100%" in done.stderr  # the bar is drawn on stderr: stdout stays the summary
    assert counted in done.stderr
    assert "left" in done.stderr


def test_run_counts_scans_without_a_total_when_the_log_does_not_say(monkeypatch):
    from typer.testing import CliRunner

    from scanlines.cli import app

    monkeypatch.setenv("FORCE_COLOR", "1")
    done = CliRunner().invoke(app, ["run", str(sample("intel")), "--jobs", "1"])
    assert done.exit_code == 0, done.output
    assert "%" not in done.stderr.split("extracting", 1)[1].split("\n", 1)[0]
    assert "scans" in done.stderr


def test_run_off_a_terminal_draws_no_bar_and_no_blank_line(tmp_path):
    """An error raised while the bar would be drawn: its one line, and no blank line."""
    log = Path(__file__).parent / "fuzz" / "corpus" / "carmen_robotlaser_stamp_3e9.log"
    out = run("run", log, "--out", tmp_path / "f.mcap")  # a stamp past 2038: no bag takes it
    lines = out.stderr.strip().splitlines()
    assert out.returncode == 2, out.stderr
    assert "" not in lines
    assert lines[-1].startswith("scanlines: error:")
    assert "extracting" not in out.stderr
