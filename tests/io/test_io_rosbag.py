"""ROS 1 and ROS 2 bags written with rosbags from real scans, read back."""

from __future__ import annotations

import math
import sqlite3
from itertools import islice

import numpy as np
import pytest
from bag_helpers import write_bag

from scanlines.data import sample
from scanlines.errors import LogFormatError
from scanlines.io import RosbagReader, open_log
from scanlines.scan import Scan

BAG_KINDS = ["ros1", "sqlite3", "mcap"]


def bag_path(tmp_path, kind):
    return tmp_path / ("scans.bag" if kind == "ros1" else f"scans_{kind}")


@pytest.fixture(scope="module")
def real_scans() -> list[Scan]:
    """20 Intel scans; the first gets REP 117 special values in beams 0-2."""
    scans = list(islice(open_log(sample("intel")), 20))
    first = scans[0]
    ranges = first.ranges.copy()
    ranges[:3] = [-np.inf, np.nan, np.inf]
    scans[0] = Scan(
        ranges,
        first.angle_min,
        first.angle_increment,
        first.range_min,
        first.range_max,
        timestamp=first.timestamp,
    )
    return scans


@pytest.mark.parametrize("kind", BAG_KINDS)
def test_round_trip(tmp_path, real_scans, kind) -> None:
    path = bag_path(tmp_path, kind)
    write_bag(path, kind, real_scans)
    reader = open_log(path)
    assert isinstance(reader, RosbagReader)
    assert reader.topic == "/scan"
    back = list(reader)
    assert len(back) == 20
    for original, scan in zip(real_scans, back, strict=True):
        np.testing.assert_array_equal(scan.ranges, original.ranges.astype(np.float32))
        assert scan.timestamp == pytest.approx(original.timestamp, abs=1e-9)
        assert scan.angle_min == float(np.float32(original.angle_min))
        assert scan.angle_increment == float(np.float32(original.angle_increment))
        assert scan.range_max == 80.0
        assert scan.pose is None
        assert scan.intensities.tolist() == list(range(180))
    first = back[0]
    assert first.ranges[0] == -math.inf
    assert math.isnan(first.ranges[1])
    assert first.ranges[2] == math.inf
    assert not first.valid[:3].any()
    assert first.ranges[3] == np.float32(2.51)


@pytest.mark.parametrize("kind", ["sqlite3", "mcap"])
def test_storage_file_directly(tmp_path, real_scans, kind) -> None:
    path = bag_path(tmp_path, kind)
    write_bag(path, kind, real_scans[:3])
    storage = next(path.glob("*.db3" if kind == "sqlite3" else "*.mcap"))
    scans = list(open_log(storage))
    assert [s.timestamp for s in scans] == pytest.approx([s.timestamp for s in real_scans[:3]])


def test_zero_stamp_falls_back_to_bag_time(tmp_path, real_scans) -> None:
    path = bag_path(tmp_path, "mcap")
    write_bag(path, "mcap", real_scans[:2], zero_stamps=True)
    stamps = [s.timestamp for s in open_log(path)]
    assert stamps == pytest.approx([s.timestamp + 1000.0 for s in real_scans[:2]], abs=1e-6)


def test_info_lists_topics(tmp_path, real_scans) -> None:
    path = bag_path(tmp_path, "ros1")
    write_bag(path, "ros1", real_scans[:4], string_topic="/notes")
    reader = open_log(path)
    info = reader.info()
    assert info["ros_version"] == 1
    assert info["scans_in_file"] == 4
    assert info["topics"] == {
        "/notes": {"type": "std_msgs/msg/String", "messages": 4},
        "/scan": {"type": "sensor_msgs/msg/LaserScan", "messages": 4},
    }
    assert sum(1 for _ in reader) == 4
    assert reader.skipped == {"/notes": 4}


@pytest.mark.parametrize("kind", BAG_KINDS)
def test_bag_without_laserscan(tmp_path, real_scans, kind) -> None:
    path = bag_path(tmp_path, kind)
    write_bag(path, kind, real_scans[:2], topics=(), string_topic="/chatter")
    with pytest.raises(LogFormatError) as caught:
        open_log(path)
    assert str(caught.value) == (
        f"{path}: no sensor_msgs/msg/LaserScan topic in this bag "
        "(topics: /chatter (std_msgs/msg/String))"
    )


def test_several_laserscan_topics_need_a_choice(tmp_path, real_scans) -> None:
    path = bag_path(tmp_path, "mcap")
    write_bag(path, "mcap", real_scans[:3], topics=("/front/scan", "/rear/scan"))
    with pytest.raises(LogFormatError) as caught:
        open_log(path)
    assert caught.value.field == "topic"
    assert "several LaserScan topics: /front/scan, /rear/scan" in str(caught.value)
    assert len(list(open_log(path, topic="/rear/scan"))) == 3
    with pytest.raises(LogFormatError, match="'/side/scan' is not a LaserScan topic"):
        open_log(path, topic="/side/scan")


def test_corrupt_bag(tmp_path) -> None:
    path = tmp_path / "broken.bag"
    path.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 64)
    with pytest.raises(LogFormatError, match=r"broken\.bag: cannot open the bag"):
        open_log(path)


@pytest.mark.parametrize("kind", ["sqlite3", "mcap"])
def test_truncated_bag(tmp_path, real_scans, kind) -> None:
    """(A truncated ROS 1 bag is read by its chunks: ``test_io_rosbag1_chunks.py``.)"""
    path = bag_path(tmp_path, kind)
    write_bag(path, kind, real_scans)
    storage = next(path.glob("*.db3" if kind == "sqlite3" else "*.mcap"))
    storage.write_bytes(storage.read_bytes()[: storage.stat().st_size // 2])
    with pytest.raises(LogFormatError) as caught:
        list(open_log(path))
    assert caught.value.path == str(path)
    assert "cannot open the bag" in str(caught.value)


def test_undecodable_message_is_a_bad_record(tmp_path, real_scans) -> None:
    path = bag_path(tmp_path, "sqlite3")
    write_bag(path, "sqlite3", real_scans)
    database = next(path.glob("*.db3"))
    with sqlite3.connect(database) as db:
        ids = [row[0] for row in db.execute("SELECT id FROM messages ORDER BY timestamp")]
        db.execute("UPDATE messages SET data = ? WHERE id = ?", (b"\x00\x01\x00\x00\x01", ids[3]))
    with pytest.raises(LogFormatError) as caught:
        list(open_log(path))
    assert caught.value.record == 4
    assert "cannot decode" in str(caught.value)
    reader = open_log(path, on_error="skip")
    indices = [index for index, _ in reader.enumerate()]
    assert indices == [i for i in range(20) if i != 3]
    assert reader.error_count == 1


def test_storage_error_mid_stream(tmp_path, real_scans, monkeypatch) -> None:
    from rosbags.highlevel import AnyReader

    path = bag_path(tmp_path, "mcap")
    write_bag(path, "mcap", real_scans[:5])
    original = AnyReader.messages

    def failing_messages(self, *args, **kwargs):
        for count, item in enumerate(original(self, *args, **kwargs)):
            if count == 2:
                raise OSError("read error")
            yield item

    monkeypatch.setattr(AnyReader, "messages", failing_messages)
    scans = []
    damaged = r"damaged after message 2 of /scan \(OSError: read error\)"
    with pytest.raises(LogFormatError, match=damaged):
        scans.extend(open_log(path))
    assert len(scans) == 2
