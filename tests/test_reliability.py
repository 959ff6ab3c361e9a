"""Regression tests of the defects found by trying scanlines as an attacker and as a new
user would: each test names the defect it guards against (D: damaged inputs, A:
parameters and geometry, S: signals and outputs, M: multiprocessing, N: newcomers)."""

from __future__ import annotations

import gzip
import json
import os
import pickle
import subprocess
import sys
import threading
import zipfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from scanlines import Extractor, LogFormatError, Scan, ScanError
from scanlines.data import sample
from scanlines.io import open_log, open_writer
from scanlines.outputs import OutputError, remove_stale_temps, temp_path

sys.path.insert(0, str(Path(__file__).parent / "io"))
from io_helpers import make_extraction

from test_cli_logs import run as cli


def one_error_line(out: subprocess.CompletedProcess, *needles: str) -> str:
    """Exit code 2 and one error line (notes such as the sensor profile's may precede it)."""
    assert out.returncode == 2, out.stderr
    assert "Traceback" not in out.stderr
    errors = [line for line in out.stderr.splitlines() if line.startswith("scanlines: error:")]
    assert len(errors) == 1, out.stderr
    assert out.stderr.strip().splitlines()[-1] == errors[0]
    for needle in needles:
        assert needle in errors[0], errors[0]
    return errors[0]


def intel_scans(count: int = 25) -> list[Scan]:
    return list(open_log(sample("intel")))[:count]


# -- D2: an MCAP that loses messages is an error, or skipped records; never a short result


@pytest.fixture(scope="module")
def damaged_mcap(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("mcap")
    whole = folder / "m.mcap"
    with open_writer(whole) as writer:
        for index, scan in enumerate(intel_scans()):
            writer.write(index, scan, make_extraction(1))
    data = whole.read_bytes()
    damaged = folder / "m0.mcap"
    damaged.write_bytes(data[:2000] + b"\0" * 13 + data[2000:])
    return damaged


def test_d2_an_mcap_losing_scans_fails_or_counts_them(damaged_mcap) -> None:
    with pytest.raises(LogFormatError, match="declares 25 messages on /scan"):
        list(open_log(damaged_mcap))
    reader = open_log(damaged_mcap, on_error="skip")
    scans = list(reader)
    info = reader.info()
    assert len(scans) + info["errors"] == info["scans_in_file"] == 25


def test_d2_run_on_the_damaged_mcap_adds_up(damaged_mcap, tmp_path) -> None:
    one_error_line(cli("run", damaged_mcap, "--out", tmp_path / "x.jsonl"), "m0.mcap")
    assert not (tmp_path / "x.jsonl").exists()
    out = cli("run", damaged_mcap, "--out", tmp_path / "y.jsonl", "--on-error", "skip")
    assert out.returncode == 0, out.stderr
    counts = json.loads((tmp_path / "y.jsonl.meta.json").read_text())["counts"]
    written = len((tmp_path / "y.jsonl").read_text().splitlines())
    assert written + counts["skipped_scan_records"] == 25
    assert "scan records skipped" in out.stdout


# -- D3-D5: damaged NPZ archives and values of the wrong type


def test_d3_a_flipped_byte_in_an_npz_is_a_clean_error(tmp_path) -> None:
    path = tmp_path / "c.npz"
    np.savez(path, ranges=np.full((100, 1000), 2.0), angle_min=0.0, angle_increment=0.001)
    data = bytearray(path.read_bytes())
    data[500000] ^= 0xFF
    path.write_bytes(bytes(data))
    for policy in ("fail", "skip"):
        with pytest.raises(LogFormatError, match=r"ranges.*damaged"):
            list(open_log(path, on_error=policy))
    one_error_line(cli("info", path), "c.npz", "ranges")


def test_d4_a_broken_npy_header_is_a_clean_error(tmp_path) -> None:
    path = tmp_path / "h.npz"
    np.savez(path, ranges=np.full((3, 10), 2.0), angle_min=0.0, angle_increment=0.01)
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    members["ranges.npy"] = members["ranges.npy"].replace(b"}", b" ", 1)
    with zipfile.ZipFile(path, "w") as archive:
        for name, content in members.items():
            archive.writestr(name, content)
    with pytest.raises(LogFormatError, match="ranges: unreadable array header"):
        list(open_log(path))


@pytest.mark.parametrize(
    "values",
    [
        {"angle_increment": "abc"},
        {"angle_increment": 1j},
        {"timestamps": np.full(3, 1j)},
        {"poses": np.full((3, 3), "x")},
        {"ranges": np.zeros((3, 10), dtype="f8,f8")},
        {"ranges": np.full((3, 10), "1.0")},
    ],
    ids=["string step", "complex step", "complex stamps", "string poses", "records", "strings"],
)
def test_d5_npz_values_of_the_wrong_type_name_the_key(tmp_path, values) -> None:
    path = tmp_path / "t.npz"
    arrays = {"ranges": np.full((3, 10), 2.0), "angle_min": 0.0, "angle_increment": 0.01}
    np.savez(path, **(arrays | values))
    with pytest.raises(LogFormatError, match=f"field {next(iter(values))}: must hold real"):
        list(open_log(path))


# -- D8: the ROS 2 writer and timestamps past 2038


def test_d8_a_timestamp_past_2038_is_a_clear_error_for_bag_output(tmp_path) -> None:
    log = tmp_path / "late.log"
    flaser = "FLASER 5 " + "1.0 " * 5 + "0 0 0 0 0 0 3000000000.0 robot 3000000000.0\n"
    log.write_text(flaser * 3)
    one_error_line(cli("run", log, "--out", tmp_path / "t.mcap"), "int32 seconds")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["late.log"]
    assert cli("run", log, "--out", tmp_path / "t.jsonl").returncode == 0


# -- D9: limits with names


def test_d9_an_enormous_line_is_a_record_error_without_reading_it_whole(tmp_path) -> None:
    path = tmp_path / "huge.log.gz"
    count = 3_000_000
    with gzip.open(path, "wt") as fh:
        fh.write(f"FLASER {count} " + "1 " * count + "0 0 0 0 0 0 1.0 robot 1.0\n")
        fh.write("FLASER 3 1 1 1 0 0 0 0 0 0 2.0 robot 2.0\n")
    with pytest.raises(LogFormatError, match=r"over the limit .*--max-beams"):
        list(open_log(path))
    reader = open_log(path, on_error="skip", max_record_bytes=1_000_000)
    assert len(list(reader)) == 1
    assert reader.bad_scans == 1
    assert "max_record_bytes" in reader.errors[0]
    out = cli("info", path, "--on-error", "skip", "--json")
    assert json.loads(out.stdout)["scans"] == 1


# -- S3: an output and its metadata commit together


def test_s3_concurrent_writers_never_mix_an_output_and_its_metadata(tmp_path) -> None:
    target = tmp_path / "out.jsonl"
    scans = intel_scans(3)

    def write(tag: int) -> None:
        for _ in range(40):
            with open_writer(target, meta={"input": f"writer {tag}"}, overwrite=True) as writer:
                for index in range(tag):
                    writer.write(index, scans[index], make_extraction(1))

    threads = [threading.Thread(target=write, args=(tag,)) for tag in (1, 2, 3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    meta = json.loads((tmp_path / "out.jsonl.meta.json").read_text())
    lines = target.read_text().splitlines()
    assert meta["input"] == f"writer {len(lines)}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.jsonl", "out.jsonl.meta.json"]


def test_s3_a_directory_in_the_way_of_the_metadata_stops_the_run_first(tmp_path) -> None:
    target = tmp_path / "out.jsonl"
    target.write_text("keep me\n")
    (tmp_path / "out.jsonl.meta.json").mkdir()
    out = cli("run", sample("intel"), "--out", target, "--overwrite")
    one_error_line(out, "is a directory")
    assert target.read_text() == "keep me\n"


# -- Output safety: no surprise replacements, no surprise folders, stale temp files


def test_an_existing_output_needs_overwrite(tmp_path) -> None:
    target = tmp_path / "out.mcap"
    target.write_bytes(b"someone's bag")
    one_error_line(cli("run", sample("intel"), "--out", target), "exists", "--overwrite")
    assert target.read_bytes() == b"someone's bag"
    out = cli("run", sample("intel"), "--scans", ":5", "--out", target, "--overwrite")
    assert out.returncode == 0, out.stderr
    assert target.read_bytes() != b"someone's bag"


def test_a_missing_folder_is_an_error_not_a_new_folder(tmp_path) -> None:
    one_error_line(
        cli("run", sample("intel"), "--out", tmp_path / "typo" / "out.jsonl"), "does not exist"
    )
    assert not (tmp_path / "typo").exists()


def test_temp_files_name_their_process_and_stale_ones_are_removed(tmp_path) -> None:
    target = tmp_path / "out.jsonl"
    mine = temp_path(target)
    assert mine.name.startswith(f".out.jsonl.{os.getpid()}.")
    dead = tmp_path / ".out.jsonl.999999999.0badf00d.tmp"
    dead_folder = tmp_path / ".out.jsonl.999999999.cafe0001.tmp"
    other = tmp_path / ".other.jsonl.999999999.0badf00d.tmp"
    for path in (mine, dead, other):
        path.write_text("partial")
    dead_folder.mkdir()
    assert sorted(remove_stale_temps(target)) == sorted([dead, dead_folder])
    assert mine.exists()
    assert other.exists()


def test_open_writer_refuses_an_existing_output_before_writing(tmp_path) -> None:
    target = tmp_path / "a.csv"
    target.write_text("x\n")
    with pytest.raises(OutputError, match="exists"):
        open_writer(target)
    assert [p.name for p in tmp_path.iterdir()] == ["a.csv"]


# -- S4: counts that add up, and the scan index of a damaged log


def test_s4_skip_counts_and_scan_indices_of_a_damaged_log(tmp_path) -> None:
    lines = gzip.decompress(sample("freiburg").read_bytes()).decode().splitlines(keepends=True)
    laser = [k for k, line in enumerate(lines) if line.startswith("FLASER")]
    odom = [k for k, line in enumerate(lines) if line.startswith("ODOM")]
    damaged = list(lines)
    for k in laser[5:12]:  # a number that is not one
        damaged[k] = damaged[k].replace(" ", " x", 3)
    for k in odom[:5]:
        damaged[k] = "ODOM 1 2\n"
    for k in laser[20:23]:  # a damaged record name
        damaged[k] = damaged[k].replace("FLASER", "FLASEX", 1)
    path = tmp_path / "damaged.log"
    path.write_text("".join(damaged))
    original = {i: s.timestamp for i, s in open_log(sample("freiburg")).enumerate()}
    reader = open_log(path, on_error="skip")
    kept = dict(reader.enumerate())
    assert len(kept) + reader.bad_scans == len(laser)
    assert reader.bad_scans == 10
    assert reader.bad_other == 5
    assert all(original[i] == scan.timestamp for i, scan in kept.items())
    out = cli("run", path, "--on-error", "skip", "--out", tmp_path / "r.jsonl")
    counts = json.loads((tmp_path / "r.jsonl.meta.json").read_text())["counts"]
    assert counts["scans"] == len(laser) - 10
    assert counts["skipped_scan_records"] == 10
    assert counts["skip_reasons"]["message name"] == 3
    assert "other records skipped" in out.stdout


# -- A5-A7: geometry


def test_a5_scans_spanning_more_than_one_turn_are_refused() -> None:
    with pytest.raises(ScanError, match="more than one turn"):
        Scan(np.ones(10), 0.0, 1e308)
    with pytest.raises(ScanError, match="more than one turn"):
        Scan(np.ones(100), 0.0, 4 * np.pi / 100)
    Scan(np.ones(361), -np.pi, 2 * np.pi / 360)  # first and last beam on one bearing: fine


def test_a7_ragged_ranges_name_the_field() -> None:
    with pytest.raises(ScanError, match="ranges must be an array of numbers"):
        Scan([[1.0, 2.0], [1.0]], 0.0, 0.01)
    with pytest.raises(ScanError, match="ranges"):
        Extractor().batch([[1.0, 2.0], [1.0]], 0.0, 0.01)


# -- M1: extractors and extractions cross process boundaries


def test_m1_a_process_pool_maps_an_extractor() -> None:
    scans = intel_scans(4)
    extractor = Extractor()
    with ProcessPoolExecutor(2) as pool:
        results = list(pool.map(extractor, scans))
    for scan, result in zip(scans, results, strict=True):
        copy = pickle.loads(pickle.dumps(result))
        assert np.array_equal(copy.first, extractor(scan).first)


# -- Newcomers


def test_n_from_laserscan_takes_ros2_and_ros1_style_messages() -> None:
    from rosbags.typesys import Stores, get_typestore

    types = get_typestore(Stores.ROS2_HUMBLE).types
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=12, nanosec=500_000_000), frame_id="l"
    )
    ranges = np.array([1.0, np.inf, 2.0, np.nan], dtype=np.float32)
    message = types["sensor_msgs/msg/LaserScan"](
        header=header, angle_min=-0.5, angle_max=0.4, angle_increment=0.3, time_increment=0.0,
        scan_time=0.0, range_min=0.1, range_max=30.0, ranges=ranges,
        intensities=np.arange(4, dtype=np.float32),
    )  # fmt: skip
    scan = Scan.from_laserscan(message)
    assert scan.timestamp == 12.5
    assert scan.valid.tolist() == [True, False, True, False]
    assert scan.intensities.tolist() == [0.0, 1.0, 2.0, 3.0]

    class Ros1Stamp:
        secs, nsecs = 3, 0

    class Ros1Header:
        stamp = Ros1Stamp()

    class Ros1Scan:
        header = Ros1Header()
        angle_min, angle_increment, range_min, range_max = 0.0, 0.1, 0.0, 10.0
        ranges, intensities = [1.0, 1.0, 1.0], []

    scan = Scan.from_laserscan(Ros1Scan())
    assert scan.timestamp == 3.0
    assert scan.intensities is None
    with pytest.raises(ScanError, match="not a sensor_msgs/LaserScan message"):
        Scan.from_laserscan(object())


def test_n_version_and_typed_package() -> None:
    import scanlines

    out = cli("--version")
    assert out.stdout.strip() == f"scanlines {scanlines.__version__}"
    assert (Path(scanlines.__file__).parent / "py.typed").exists()


def test_n_option_choices_show_in_help() -> None:
    out = cli("run", "--help")
    assert "fail|skip" in out.stdout
    assert "sensor|world" in out.stdout
    assert "adaptive|" in out.stdout


def test_n_the_csv_geometry_message_says_both_units(tmp_path) -> None:
    path = tmp_path / "s.csv"
    path.write_text("1,2,3\n")
    one_error_line(cli("info", path), "radians", "degrees on the command line")


def test_n_plot_pages_a_long_selection(tmp_path) -> None:
    out = cli("plot", sample("intel"), "--scans", "0:30", "-o", tmp_path / "p.png")
    assert out.returncode == 0, out.stderr
    assert "drew 30 scans" in out.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p-2.png", "p-3.png", "p.png"]
    out = cli("plot", sample("intel"), "--scans", "0:30", "-o", tmp_path / "p.png")
    one_error_line(out, "exists")
    out = cli(
        "plot", sample("intel"), "--scans", "::2", "--max-pages", "1", "-o", tmp_path / "q.png"
    )
    assert "138 more selected, past --max-pages" in out.stdout


def test_angle_min_in_degrees_is_caught() -> None:
    with pytest.raises(ScanError, match="degrees given as radians"):
        Scan(np.ones(181), -90.0, np.radians(1.0))
