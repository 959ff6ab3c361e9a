"""open_log: choosing the reader, and the file-level errors."""

from __future__ import annotations

import gzip
import shutil
import subprocess
import sys

import numpy as np
import pytest

from scanlines.data import sample
from scanlines.errors import LogFormatError, ParameterError
from scanlines.io import detect_format, open_log, reader_option_names


@pytest.mark.parametrize(
    ("name", "fmt"),
    [
        ("intel.clf.gz", "carmen"),
        ("intel.log", "carmen"),
        ("intel.clf", "carmen"),
        ("intel.gz", "carmen"),
        ("intel", "carmen"),
        ("intel.data", "carmen"),
    ],
)
def test_carmen_by_name_or_content(tmp_path, name, fmt) -> None:
    path = tmp_path / name
    source = sample("intel")
    if name.endswith(".gz"):
        shutil.copy(source, path)
    else:
        path.write_bytes(gzip.decompress(source.read_bytes()))
    assert detect_format(path) == fmt
    assert sum(1 for _ in open_log(path)) == 300


@pytest.mark.parametrize(
    ("name", "fmt"),
    [
        ("exp1.dat.gz", "coreslam"),
        ("exp1.gz", "coreslam"),
        ("exp1.dat", "coreslam"),
        ("exp1", "coreslam"),
    ],
)
def test_coreslam_by_name_or_content(tmp_path, fixtures, name, fmt) -> None:
    path = tmp_path / name
    data = (fixtures / "exp1_first30.dat.gz").read_bytes()
    path.write_bytes(data if name.endswith(".gz") else gzip.decompress(data))
    assert detect_format(path) == fmt
    assert sum(1 for _ in open_log(path)) == 30


def test_table_and_npz_by_content(tmp_path, fixtures) -> None:
    table = tmp_path / "ranges"
    table.write_text("1.0,2.0,3.0\n")
    assert detect_format(table) == "csv"
    stack = tmp_path / "stack.npz"
    shutil.copy(fixtures / "intel_every5th_rows1098-1109.npz", stack)
    assert detect_format(stack) == "npz"


def test_empty_file(fixtures) -> None:
    path = fixtures / "empty.log"
    with pytest.raises(LogFormatError) as caught:
        open_log(path)
    assert str(caught.value) == f"{path}: the file is empty"


def test_empty_gzip(tmp_path) -> None:
    path = tmp_path / "nothing.log.gz"
    path.write_bytes(gzip.compress(b""))
    with pytest.raises(LogFormatError, match=r"nothing\.log\.gz: the file holds no data"):
        open_log(path)


def test_unknown_format(fixtures) -> None:
    path = fixtures / "unknown.xyz"
    with pytest.raises(LogFormatError) as caught:
        open_log(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: unknown log format (first record 'hello world')")
    assert "CARMEN log" in message
    assert "ROS 2 bag" in message


def test_name_contradicting_content(fixtures, tmp_path) -> None:
    path = tmp_path / "ranges.log"
    path.write_text("1.0 2.0 3.0\n")
    with pytest.raises(
        LogFormatError, match=r"the name says CARMEN log .* first record is '1.0 2.0 3.0'"
    ):
        open_log(path)


def test_bag_magic_with_wrong_suffix(tmp_path) -> None:
    path = tmp_path / "run.log"
    path.write_bytes(b"#ROSBAG V2.0\n....")
    with pytest.raises(LogFormatError, match=r"name it with the suffix \.bag"):
        open_log(path)


def test_directory_that_is_not_a_bag(tmp_path) -> None:
    with pytest.raises(LogFormatError, match="not a ROS 2 bag"):
        open_log(tmp_path)


def test_missing_file(tmp_path) -> None:
    with pytest.raises(LogFormatError, match="no such file"):
        open_log(tmp_path / "absent.log")


class TestTruncatedGzip:
    def test_error_names_file_and_line_after_the_good_records(self, fixtures) -> None:
        path = fixtures / "truncated.clf.gz"
        reader = open_log(path)  # the head decompresses fine
        scans = []
        with pytest.raises(LogFormatError) as caught:
            scans.extend(reader)
        assert caught.value.path == str(path)
        assert "gzip data is truncated or corrupt" in str(caught.value)
        assert 50 < len(scans) < 300
        assert caught.value.record == len(scans) + 6 + 1  # 6 comment lines, then the cut line

    def test_skip_mode_still_raises(self, fixtures) -> None:
        with pytest.raises(LogFormatError, match="truncated"):
            list(open_log(fixtures / "truncated.clf.gz", on_error="skip"))

    def test_cut_inside_the_gzip_header(self, tmp_path) -> None:
        path = tmp_path / "cut.clf.gz"
        path.write_bytes(sample("intel").read_bytes()[:12])
        with pytest.raises(LogFormatError, match=r"cut\.clf\.gz: the gzip data is truncated"):
            open_log(path)


def test_option_of_another_format(fixtures) -> None:
    with pytest.raises(ParameterError, match="topic do not apply to carmen logs"):
        open_log(sample("intel"), topic="/scan")


def test_forced_format(tmp_path) -> None:
    path = tmp_path / "scans.weird"
    np.savetxt(path, np.ones((2, 3)), delimiter=",")
    scans = list(open_log(path, format="csv", angle_min=0.0, angle_increment=0.1))
    assert len(scans) == 2
    with pytest.raises(ParameterError, match="unknown format 'excel'"):
        open_log(path, format="excel")


def test_reader_option_names_lists_keywords() -> None:
    assert reader_option_names("carmen") == [
        "message",
        "fov",
        "angle_convention",
        "max_range",
        "range_max",
        "range_min",
        "pose",
        "mounting",
        "timestamp",
        "on_error",
        "max_beams",
        "max_record_bytes",
    ]
    assert reader_option_names("rosbag") == ["topic", "on_error", "max_beams", "max_record_bytes"]


def test_import_does_not_import_rosbags() -> None:
    code = "import sys, scanlines.io; print('rosbags' in sys.modules)"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "False"
