"""An MCAP whose records declare more bytes than the file holds: the error says which
record, at which byte offset, is damaged (rosbags alone said ``MemoryError``)."""

from __future__ import annotations

import struct
from itertools import islice
from pathlib import Path

import pytest
from bag_helpers import write_bag

from cli_helpers import scanlines
from scanlines.data import sample
from scanlines.errors import LogFormatError
from scanlines.io import open_log
from scanlines.io.mcap_records import mcap_damage

HUGE = 2**40
FOOTER = 37  # the footer record (29 bytes) and the closing magic


@pytest.fixture(scope="module")
def mcap_bytes(tmp_path_factory) -> bytes:
    """A 10-scan MCAP file as the tests' bag writer writes it (one chunk, a summary)."""
    folder = tmp_path_factory.mktemp("mcap") / "bag"
    write_bag(folder, "mcap", list(islice(open_log(sample("intel")), 10)))
    (storage,) = folder.glob("*.mcap")
    return storage.read_bytes()


def records(data: bytes, start: int = 8) -> list[tuple[int, int, int]]:
    """``(opcode, offset, length)`` of the file's top-level records, after the magic."""
    found, offset = [], start
    while offset < len(data) - 8:
        opcode, length = data[offset], struct.unpack_from("<Q", data, offset + 1)[0]
        found.append((opcode, offset, length))
        offset += 9 + length
    return found


def first(data: bytes, opcode: int, after: int = 0) -> int:
    return next(offset for op, offset, _ in records(data) if op == opcode and offset >= after)


def summary_start(data: bytes) -> int:
    return struct.unpack_from("<Q", data, len(data) - FOOTER + 9)[0]


def with_length(data: bytes, offset: int, length: int) -> bytes:
    return data[: offset + 1] + struct.pack("<Q", length) + data[offset + 9 :]


def write(tmp_path: Path, data: bytes, name: str = "damaged.mcap") -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


@pytest.mark.parametrize(("opcode", "kind"), [(0x03, "schema"), (0x04, "channel")])
def test_a_summary_record_declaring_2e40_bytes_is_named_at_its_offset(
    mcap_bytes, tmp_path, opcode, kind
) -> None:
    offset = first(mcap_bytes, opcode, after=summary_start(mcap_bytes))
    path = write(tmp_path, with_length(mcap_bytes, offset, HUGE))
    expected = f"the {kind} record at byte {offset} declares {HUGE} bytes, but"
    for policy in ("fail", "skip"):
        with pytest.raises(LogFormatError) as error:
            open_log(path, on_error=policy)
        message = str(error.value)
        assert message.startswith(f"{path}: cannot open the bag: {expected}"), message
        assert "MemoryError" not in message
    for command in ("info", "run"):
        out = scanlines(command, path)
        assert out.returncode == 2, out.stderr
        lines = out.stderr.strip().splitlines()
        assert len(lines) == 1, out.stderr
        assert expected in lines[0]


def test_a_schema_field_longer_than_its_record_is_named(mcap_bytes, tmp_path) -> None:
    offset = first(mcap_bytes, 0x03, after=summary_start(mcap_bytes))
    name_length = struct.unpack_from("<I", mcap_bytes, offset + 11)[0]
    at = offset + 9 + 2 + 4 + name_length  # the encoding field's length
    data = mcap_bytes[:at] + struct.pack("<I", 2**31) + mcap_bytes[at + 4 :]
    path = write(tmp_path, data)
    with pytest.raises(LogFormatError, match=rf"schema record at byte {offset}: its encoding"):
        open_log(path)


def test_without_a_summary_the_data_section_is_checked(mcap_bytes, tmp_path) -> None:
    """An MCAP without a summary section is opened by reading its data section."""
    data = mcap_bytes[: len(mcap_bytes) - FOOTER + 9] + struct.pack("<Q", 0)
    data += mcap_bytes[len(mcap_bytes) - FOOTER + 17 :]
    chunk = first(data, 0x06)
    path = write(tmp_path, with_length(data, chunk, HUGE))
    with pytest.raises(LogFormatError, match=rf"the chunk record at byte {chunk} declares"):
        open_log(path)


def test_a_bag_directory_names_its_damaged_file(mcap_bytes, tmp_path) -> None:
    folder = tmp_path / "bag"
    folder.mkdir()
    offset = first(mcap_bytes, 0x04, after=summary_start(mcap_bytes))
    write(folder, with_length(mcap_bytes, offset, HUGE), "bag_0.mcap")
    with pytest.raises(LogFormatError, match=rf"bag_0.mcap: the channel record at byte {offset}"):
        open_log(folder)


def test_whole_mcap_files_are_not_damaged(mcap_bytes, tmp_path) -> None:
    assert mcap_damage(write(tmp_path, mcap_bytes, "whole.mcap")) is None
    assert len(list(open_log(tmp_path / "whole.mcap"))) == 10
