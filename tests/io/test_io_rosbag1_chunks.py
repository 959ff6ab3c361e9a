"""ROS 1 bags whose index disagrees with their data, cut short, or damaged: read by their
chunks (as ``rosbag reindex`` would), every loss said, every damage located."""

from __future__ import annotations

import struct
import subprocess
import sys
from itertools import islice
from pathlib import Path

import pytest
from bag_helpers import write_bag

from cli_helpers import scanlines
from scanlines.data import sample
from scanlines.errors import LogFormatError
from scanlines.io import open_log
from scanlines.scan import Scan

SCANS = 30


@pytest.fixture(scope="module")
def bag_data(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """A ROS 1 bag of 30 Intel scans in 6 chunks of 5 (bytes)."""
    scans: list[Scan] = list(islice(open_log(sample("intel")), SCANS))
    path = tmp_path_factory.mktemp("bag") / "scans.bag"
    write_bag(path, "ros1", scans, chunk_bytes=8000)
    return path.read_bytes()


def records(data: bytes) -> list[tuple[int, int, int, dict[str, bytes]]]:
    """``(offset, header length, op, header fields)`` of each top-level record."""
    out, offset = [], len(b"#ROSBAG V2.0\n")
    while offset < len(data):
        (header_length,) = struct.unpack_from("<I", data, offset)
        raw, fields, pos = data[offset + 4 : offset + 4 + header_length], {}, 0
        while pos < len(raw):
            (n,) = struct.unpack_from("<I", raw, pos)
            name, _, value = raw[pos + 4 : pos + 4 + n].partition(b"=")
            fields[name.decode()] = value
            pos += 4 + n
        (data_length,) = struct.unpack_from("<I", data, offset + 4 + header_length)
        out.append((offset, header_length, fields["op"][0], fields))
        offset += 8 + header_length + data_length
    return out


def field_offset(data: bytes, record_offset: int, name: str) -> int:
    """The offset of the value of header field ``name`` of the record at ``record_offset``."""
    (header_length,) = struct.unpack_from("<I", data, record_offset)
    at = data.index(name.encode() + b"=", record_offset + 4, record_offset + 4 + header_length)
    return at + len(name) + 1


def chunk_counts(data: bytes) -> list[int]:
    """Messages in each chunk, from the index-data record after it."""
    return [struct.unpack("<I", f["count"])[0] for _, _, op, f in records(data) if op == 0x04]


def put_u32(data: bytes, at: int, value: int) -> bytes:
    return data[:at] + struct.pack("<I", value) + data[at + 4 :]


def write(tmp_path: Path, data: bytes, name: str = "scans.bag") -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("on_error", ["fail", "skip"])
def test_lowered_chunk_count_reads_every_scan(tmp_path, bag_data, on_error) -> None:
    """The bag header says 4 chunks of 6: the index lists fewer messages than the data."""
    header = records(bag_data)[0]
    assert header[2] == 0x03
    data = put_u32(bag_data, field_offset(bag_data, header[0], "chunk_count"), 4)
    reader = open_log(write(tmp_path, data), on_error=on_error)
    scans = list(reader)
    assert len(scans) == SCANS
    assert [s.timestamp for s in scans] == sorted(s.timestamp for s in scans)
    info = reader.info()
    assert info["scans_in_file"] == SCANS
    assert info["errors"] == 0
    listed = sum(chunk_counts(bag_data)[:4])
    assert listed < SCANS
    assert f"/scan: {listed} in the index, 30 in the chunks" in info["index_note"]


def test_zeroed_chunk_info_count_reads_every_scan(tmp_path, bag_data) -> None:
    last_info = [r for r in records(bag_data) if r[2] == 0x06][-1]
    data = put_u32(bag_data, field_offset(bag_data, last_info[0], "count"), 0)
    reader = open_log(write(tmp_path, data))
    assert len(list(reader)) == SCANS
    listed = SCANS - chunk_counts(bag_data)[-1]
    assert f"/scan: {listed} in the index, 30 in the chunks" in reader.info()["index_note"]


@pytest.mark.parametrize("compression", ["bz2", "lz4"])
def test_compressed_chunks_are_read_by_their_data(tmp_path, compression) -> None:
    scans = list(islice(open_log(sample("intel")), SCANS))
    path = tmp_path / "packed.bag"
    write_bag(path, "ros1", scans, chunk_bytes=8000, compression=compression)
    data = path.read_bytes()
    lowered = put_u32(data, field_offset(data, records(data)[0][0], "chunk_count"), 2)
    reader = open_log(write(tmp_path, lowered, "lowered.bag"))
    back = list(reader)
    assert [s.ranges.tolist() for s in back] == [s.ranges.tolist() for s in open_log(path)]
    assert len(back) == SCANS
    assert "in the index, 30 in the chunks" in reader.info()["index_note"]


def test_sound_bag_is_read_through_its_index(tmp_path, bag_data) -> None:
    reader = open_log(write(tmp_path, bag_data))
    assert len(list(reader)) == SCANS
    assert "index_note" not in reader.info()


def truncated(bag_data: bytes) -> tuple[bytes, int]:
    """The bag cut 100 bytes into its fourth chunk's data (the first three whole)."""
    fourth = [r for r in records(bag_data) if r[2] == 0x05][3]
    cut = fourth[0] + 8 + fourth[1] + 100
    return bag_data[:cut], cut


def test_truncated_bag_fails_naming_the_byte(tmp_path, bag_data) -> None:
    data, _ = truncated(bag_data)
    path = write(tmp_path, data)
    scans = []
    with pytest.raises(LogFormatError) as caught:
        scans.extend(open_log(path))
    held = sum(chunk_counts(bag_data)[:3])
    assert len(scans) == held
    message = str(caught.value)
    assert message.startswith(f"{path}, message {held + 1}: the bag is truncated at byte ")
    assert f"{held} messages of /scan read before it" in message


def test_truncated_bag_yields_what_it_holds_when_skipping(tmp_path, bag_data) -> None:
    data, cut = truncated(bag_data)
    held = sum(chunk_counts(bag_data)[:3])
    reader = open_log(write(tmp_path, data), on_error="skip")
    assert len(list(reader)) == held
    info = reader.info()
    assert info["errors"] == 1
    assert info["scans_in_file"] == held + 1  # those read and the record cut short
    assert "the bag ends at byte" in info["index_note"]
    assert f"of {cut}" in info["index_note"]
    assert "truncated" in reader.errors[0]


def test_truncated_bag_through_the_command(tmp_path, bag_data) -> None:
    data, _ = truncated(bag_data)
    path = write(tmp_path, data)
    out = tmp_path / "out.jsonl"
    done = scanlines("run", path, "--out", out, "--on-error", "skip")
    assert done.returncode == 0, done.stderr
    assert len(out.read_text().splitlines()) == sum(chunk_counts(bag_data)[:3])
    assert "truncated" in done.stdout + done.stderr


@pytest.mark.parametrize("length", [2**31, 2**32 - 1])
def test_damaged_length_names_the_byte(tmp_path, bag_data, length) -> None:
    """The header length of the third chunk record set absurdly high: damage at its byte;
    the other chunks read (the index places the next one), the third's counted as lost."""
    third = [r for r in records(bag_data) if r[2] == 0x05][2]
    path = write(tmp_path, put_u32(bag_data, third[0], length))
    with pytest.raises(LogFormatError) as caught:
        list(open_log(path))
    assert f"the bag is damaged at byte {third[0]}" in str(caught.value)
    assert "MemoryError" not in str(caught.value)
    counts = chunk_counts(bag_data)
    assert f"message {sum(counts[:2]) + 1}:" in str(caught.value)
    assert f"{counts[2]} more that the index lists are lost" in str(caught.value)
    reader = open_log(path, on_error="skip")
    assert len(list(reader)) == SCANS - counts[2]
    assert reader.error_count == counts[2]
    assert reader.info()["scans_in_file"] == 30


def test_damaged_index_reads_the_data(tmp_path, bag_data) -> None:
    """A damaged length in the index section: the chunks are whole, every scan is read."""
    connection = next(r for r in records(bag_data) if r[2] == 0x07)
    path = write(tmp_path, put_u32(bag_data, connection[0], 2**31))
    reader = open_log(path)
    assert len(list(reader)) == SCANS
    assert f"damaged at byte {connection[0]}" in reader.info()["index_note"]


def test_damaged_first_chunk_header(tmp_path, bag_data) -> None:
    first = next(r for r in records(bag_data) if r[2] == 0x05)
    path = write(tmp_path, put_u32(bag_data, first[0], 2**31))
    with pytest.raises(LogFormatError, match=f"message 1: the bag is damaged at byte {first[0]}"):
        list(open_log(path))
    reader = open_log(path, on_error="skip")
    assert len(list(reader)) == SCANS - chunk_counts(bag_data)[0]


def test_unindexed_damage_is_one_lost_record(tmp_path, bag_data) -> None:
    """Damage inside the second chunk of a bag without its index: the walk goes on at the
    chunk's end; the damage counts as one record lost."""
    second = [r for r in records(bag_data) if r[2] == 0x05][1]
    first_message = second[0] + 8 + second[1]
    index_pos = field_offset(bag_data, records(bag_data)[0][0], "index_pos")
    data = bag_data[:index_pos] + bytes(8) + bag_data[index_pos + 8 :]
    data = put_u32(data, first_message, 2**31 - 5)  # the first message record's header
    reader = open_log(write(tmp_path, data), on_error="skip")
    assert len(list(reader)) == SCANS - chunk_counts(bag_data)[1]
    assert reader.error_count == 1
    assert reader.info()["scans_in_file"] == SCANS - chunk_counts(bag_data)[1] + 1


@pytest.mark.parametrize("where", ["into a chunk", "past the end", "zero"])
def test_a_wrong_index_pos_reads_the_data(tmp_path, bag_data, where) -> None:
    """``index_pos`` pointing into a chunk, past the end of the file, or 0 (not indexed):
    every chunk is still read."""
    header = records(bag_data)[0]
    at = field_offset(bag_data, header[0], "index_pos")
    second = [r for r in records(bag_data) if r[2] == 0x05][1]
    value = {"into a chunk": second[0] + 50, "past the end": len(bag_data) + 99, "zero": 0}
    data = bag_data[:at] + struct.pack("<Q", value[where]) + bag_data[at + 8 :]
    reader = open_log(write(tmp_path, data), on_error="skip")
    assert len(list(reader)) == SCANS
    assert reader.error_count == 0
    assert reader.info()["index_note"].startswith("the bag cannot be read through its index")


def test_damage_inside_a_chunk_of_an_indexed_bag(tmp_path, bag_data) -> None:
    """A message record inside the second chunk with a wrong op code: the chunks are
    counted by their index data, so this damage is met while reading; it is located, and
    the rest of that chunk is counted as lost."""
    second = [r for r in records(bag_data) if r[2] == 0x05][1]
    start = second[0] + 8 + second[1]
    (length,) = struct.unpack_from("<I", bag_data, start - 4)
    ops = [m for m in range(start, start + length) if bag_data.startswith(b"op=\x02", m)]
    at = ops[2] + 3  # the third message of the chunk
    path = write(tmp_path, bag_data[:at] + b"\x09" + bag_data[at + 1 :])
    first = chunk_counts(bag_data)[0]
    scans = []
    with pytest.raises(LogFormatError, match=f"message {first + 3}: the bag is damaged"):
        scans.extend(open_log(path))
    assert len(scans) == first + 2
    reader = open_log(path, on_error="skip")
    lost = chunk_counts(bag_data)[1] - 2
    assert len(list(reader)) == SCANS - lost
    assert reader.error_count == lost
    assert reader.info()["scans_in_file"] == SCANS


def test_topic_names_are_compared_as_rosbags_names_them(tmp_path) -> None:
    """A topic written ``//front//scan`` is ``/front/scan`` to rosbags and to the walk:
    a sound bag is not taken for one whose index disagrees."""
    path = tmp_path / "slashes.bag"
    write_bag(path, "ros1", list(islice(open_log(sample("intel")), 3)), topics=("//front//scan",))
    reader = open_log(path)
    assert reader.topic == "/front/scan"
    assert len(list(reader)) == 3
    assert "index_note" not in reader.info()


def test_a_damaged_length_in_a_small_address_space(tmp_path, bag_data) -> None:
    """Under a 1 GB address-space limit a header length of 2^31 made rosbags fail with
    MemoryError ("cannot open the bag (MemoryError)"); the walk checks it against the file
    first, locates the damage and reads the other chunks."""
    third = [r for r in records(bag_data) if r[2] == 0x05][2]
    path = write(tmp_path, put_u32(bag_data, third[0], 2**31))
    code = (
        "import resource, sys\n"
        "resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))\n"
        "from scanlines.io import open_log\n"
        "reader = open_log(sys.argv[1], on_error='skip')\n"
        "print(len(list(reader)), reader.errors[0])\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    read, message = done.stdout.split(" ", 1)
    assert int(read) == SCANS - chunk_counts(bag_data)[2]
    assert f"the bag is damaged at byte {third[0]}" in message
    assert "MemoryError" not in done.stdout
