"""What ``info`` and ``run`` say: flags by their names, readable fields and dates, an
unknown output refused before the log is read, no numpy warning, every decision noted."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from itertools import islice
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent / "io"))
from bag_helpers import write_bag

from cli_helpers import Ran
from cli_helpers import scanlines as in_process
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.scan import Scan


def scanlines(*args: object, warnings_as_errors: bool = False) -> Ran | subprocess.CompletedProcess:
    """The command in this process, or in a process of its own where numpy's warnings
    must be errors (a process's ``-W`` reaches every module)."""
    if not warnings_as_errors:
        return in_process(*args, columns=200)
    return subprocess.run(
        [sys.executable, "-W", "error::RuntimeWarning", "-m", "scanlines", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "COLUMNS": "200"},
    )


def intel(count: int) -> list[Scan]:
    return list(islice(open_log(sample("intel")), count))


def test_an_unknown_output_suffix_is_refused_before_the_log_is_read(tmp_path) -> None:
    broken = tmp_path / "broken.bag"
    broken.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 64)
    out = scanlines("run", broken, "--out", tmp_path / "features.xyz")
    assert out.returncode == 2
    assert "unknown output format '.xyz'" in out.stderr
    assert "cannot open the bag" not in out.stderr


def test_run_without_out_says_it_writes_nothing() -> None:
    out = scanlines("run", sample("intel"), "--scans", "0:5")
    assert out.returncode == 0, out.stderr
    assert out.stderr.strip().splitlines()[-1].startswith("scanlines: no --out given")
    assert "not written" in out.stderr
    assert "none (no --out given)" in out.stdout


def test_an_error_without_out_is_still_one_line(tmp_path) -> None:
    broken = tmp_path / "broken.bag"
    broken.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 64)
    out = scanlines("run", broken)
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr


def test_a_taken_output_names_the_flag(tmp_path) -> None:
    target = tmp_path / "out.jsonl"
    target.write_text("")
    out = scanlines("run", sample("intel"), "--scans", "0:2", "--out", target)
    assert out.returncode == 2
    assert "--overwrite" in out.stderr
    assert "overwrite=True" not in out.stderr


def test_several_topics_name_the_flag(tmp_path) -> None:
    path = tmp_path / "two"
    write_bag(path, "mcap", intel(2), topics=("/front/scan", "/rear/scan"))
    out = scanlines("info", path)
    assert out.returncode == 2
    assert "choose one with --topic" in out.stderr
    assert "topic=..." not in out.stderr


def test_huge_ranges_leak_no_numpy_warning(tmp_path) -> None:
    table = tmp_path / "huge.csv"
    table.write_text(
        "# angle_min=0 angle_increment=0.01\n# range_max=1e308\ntimestamp,r0,r1,r2\n"
        "1,1e308,1e308,1\n2,1e308,1e308,1e308\n"
    )
    out = scanlines("info", table, "--json", warnings_as_errors=True)
    assert out.returncode == 0, out.stderr
    assert "Warning" not in out.stderr
    mean = re.search(r'"range_mean": ([^,]+),', out.stdout).group(1)
    assert float(mean) == pytest.approx(1e308 / 6 * 5)


def test_info_of_a_bag_prints_topics_and_dates(tmp_path) -> None:
    scans = [
        Scan(s.ranges, s.angle_min, s.angle_increment, s.range_min, s.range_max,
             timestamp=1_764_754_200.0 + k * 0.1)
        for k, s in enumerate(intel(3))
    ]  # fmt: skip
    path = tmp_path / "epoch.bag"
    write_bag(path, "ros1", scans, string_topic="/notes")
    out = scanlines("info", path)
    assert out.returncode == 0, out.stderr
    assert "{'" not in out.stdout
    assert "/scan: sensor_msgs/msg/LaserScan, 3 messages" in out.stdout
    assert "2025-12-03T09:30:00.000Z .. 2025-12-03T09:30:00.200Z" in out.stdout


def sick_stack(path: Path, *, range_max: bool) -> None:
    scans = intel(40)
    ranges = np.array([np.where(np.isnan(s.ranges), 81.83, s.ranges) for s in scans])
    extra = {"range_max": 80.0} if range_max else {}
    np.savez(path, ranges=ranges, angle_min=scans[0].angle_min,
             angle_increment=scans[0].angle_increment, **extra)  # fmt: skip


def test_npz_without_range_max_reads_the_sick_code_as_no_return(tmp_path) -> None:
    path = tmp_path / "sick.npz"
    sick_stack(path, range_max=False)
    reader = open_log(path)
    scans = list(reader)
    assert max(float(np.nanmax(s.ranges[s.valid])) for s in scans) < 81.0
    assert reader.no_return_code == 81.83
    assert "no range_max key" in reader.info()["notes"][0]
    out = scanlines("run", path, "--out", tmp_path / "features.jsonl")
    assert out.returncode == 0, out.stderr
    assert "no range_max key" in out.stdout
    help_text = scanlines("run", "--help").stdout
    assert "range_max" in re.sub(r"\s+", " ", help_text)


def test_npz_with_range_max_is_untouched(tmp_path) -> None:
    path = tmp_path / "sick.npz"
    sick_stack(path, range_max=True)
    reader = open_log(path)
    assert reader.no_return_code is None
    assert "notes" not in reader.info()


def test_npz_without_a_repeated_top_range_is_untouched(tmp_path) -> None:
    scans = intel(5)
    path = tmp_path / "plain.npz"
    np.savez(path, ranges=np.array([np.where(s.valid, s.ranges, 1.0) for s in scans]),
             angle_min=0.0, angle_increment=0.01)  # fmt: skip
    assert open_log(path).no_return_code is None


def test_an_absurd_declared_count_is_not_reported_as_skipped(tmp_path) -> None:
    path = tmp_path / "bag"
    write_bag(path, "mcap", intel(30))
    metadata = path / "metadata.yaml"
    metadata.write_text(
        metadata.read_text().replace("message_count: 30", "message_count: 99999999999")
    )
    reader = open_log(path, on_error="skip")
    assert len(list(reader)) == 30
    info = reader.info()
    assert info["errors"] == 0
    assert info["scans_in_file"] == 30
    assert "99999999999 messages on /scan, more than its" in info["notes"][0]
    out = scanlines("run", path, "--on-error", "skip", "--out", tmp_path / "f.jsonl")
    assert out.returncode == 0, out.stderr
    assert "99999999969" not in out.stdout


@pytest.fixture(autouse=True)
def _no_leftovers(tmp_path):
    yield
    shutil.rmtree(tmp_path, ignore_errors=True)


def limited(*args: object) -> subprocess.CompletedProcess:
    """``scanlines ARGS`` with files limited to 20 kB (as a full disk would stop them):
    writes past it fail with EFBIG."""
    import resource

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))

    return subprocess.run(
        [sys.executable, "-m", "scanlines", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=limit,
        env={**os.environ, "COLUMNS": "200"},
    )


def test_a_write_error_names_the_output(tmp_path) -> None:
    target = tmp_path / "features.jsonl"
    out = limited("run", sample("intel"), "--out", target)
    assert out.returncode == 2, out.stderr
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith(f"scanlines: error: {target}: cannot write the output")
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_parquet_write_error_names_the_part_on_stderr_and_leaves_no_folder(tmp_path) -> None:
    pytest.importorskip("pyarrow")
    logs = tmp_path / "logs"
    logs.mkdir()
    shutil.copy(sample("intel"), logs)
    dataset = tmp_path / "features"
    out = limited("run", logs, "--out", dataset, "--format", "parquet", "-j", "1")
    assert out.returncode == 2, out.stderr
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith("scanlines: error: intel_excerpt.clf.gz: ")
    assert f"{dataset}/_staging/segments/log=intel_excerpt.clf.gz/part-" in last
    assert "cannot write the part" in last
    assert not dataset.exists()
