"""The records of an MCAP file that opening it reads, checked before rosbags reads them.

rosbags reads a record by allocating the length the record declares: a damaged length
(a schema record claiming 2^40 bytes) is a ``MemoryError`` or an ``OverflowError``
there, which says nothing of where the file is damaged. :func:`mcap_damage` walks the
same records first (their lengths only: a seek per record, and the small schema and
channel records read whole) and names the first record whose lengths the file cannot
hold, by its kind and byte offset.

What opening reads (``rosbags.rosbag2.storage_mcap.McapReader.open``): the header record,
the footer, and the summary section's records; without a summary section (or without a
schema record in it), the data section's records, chunks included by their own header.
Messages inside chunks are read later, from the chunk's bytes in memory, where a wrong
length cannot allocate more than the chunk holds.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from scanlines.errors import LogFormatError, describe

__all__ = ["MAGIC", "RECORD_NAMES", "check_mcap_records", "mcap_damage", "mcap_files"]

MAGIC = b"\x89MCAP0\r\n"
#: Opcode -> the record's name in the MCAP specification.
RECORD_NAMES = {
    0x01: "header",
    0x02: "footer",
    0x03: "schema",
    0x04: "channel",
    0x05: "message",
    0x06: "chunk",
    0x07: "message index",
    0x08: "chunk index",
    0x09: "attachment",
    0x0A: "attachment index",
    0x0B: "statistics",
    0x0C: "metadata",
    0x0D: "metadata index",
    0x0E: "summary offset",
    0x0F: "data end",
}
#: The footer record and the closing magic: opcode, length, two offsets, a CRC, magic.
FOOTER_BYTES = 1 + 8 + 8 + 8 + 4 + len(MAGIC)
#: Record kinds whose content :func:`_fields_damage` reads: schema and channel.
_SCHEMA, _CHANNEL, _CHUNK = 0x03, 0x04, 0x06


def mcap_files(path: Path) -> list[Path]:
    """The MCAP files of a bag path: the file itself, or those of a bag directory."""
    if path.is_dir():
        return sorted(p for p in path.iterdir() if p.suffix == ".mcap" and p.is_file())
    return [path] if path.suffix == ".mcap" and path.is_file() else []


def check_mcap_records(bag: Path) -> None:
    """Raise a :class:`~scanlines.LogFormatError` naming the first damaged record (its
    kind and byte offset) of the MCAP file ``bag`` or of those of the bag directory
    ``bag``; nothing for other bags."""
    for path in mcap_files(bag):
        try:
            damage = mcap_damage(path)
        except OSError as exc:
            raise LogFormatError(f"cannot read the bag ({describe(exc)})", path=bag) from None
        if damage is not None:
            where = "" if path == bag else f"{path.name}: "
            raise LogFormatError(f"cannot open the bag: {where}{damage}", path=bag)


def mcap_damage(path: Path) -> str | None:
    """Where the records that opening ``path`` reads are damaged (which record, at which
    byte offset, and why), or ``None``: nothing found (what this does not check,
    rosbags reports)."""
    size = path.stat().st_size
    with open(path, "rb") as fh:
        if fh.read(len(MAGIC)) != MAGIC or size < len(MAGIC) + 9 + FOOTER_BYTES:
            return None  # not an MCAP file, or too short to hold one: rosbags says so
        footer_start = size - FOOTER_BYTES
        fh.seek(footer_start)
        footer = fh.read(FOOTER_BYTES)
        if footer[:9] != b"\x02" + struct.pack("<Q", 20) or footer[-len(MAGIC) :] != MAGIC:
            return None  # rosbags names a missing footer
        (summary_start,) = struct.unpack_from("<Q", footer, 9)
        header = next(_records(fh, len(MAGIC), footer_start, first_only=True))
        if isinstance(header, str):
            return header
        data_start = len(MAGIC) + 9 + header[2]
        if summary_start and not data_start <= summary_start <= footer_start:
            return None  # rosbags names a summary offset out of the file
        schemas = 0
        if summary_start:
            for item in _records(fh, summary_start, footer_start, stop=(0x02, 0x0E)):
                if isinstance(item, str):
                    return item
                schemas += item[0] == _SCHEMA
        if summary_start and schemas:
            return None  # opening reads the summary only
        end, where = (summary_start, "the summary") if summary_start else (footer_start, None)
        for item in _records(fh, data_start, end, end_name=where or "the footer"):
            if isinstance(item, str):
                return item
    return None


def _records(
    fh: BinaryIO,
    start: int,
    end: int,
    *,
    stop: tuple[int, ...] = (),
    first_only: bool = False,
    end_name: str = "the footer",
) -> Iterator[tuple[int, int, int] | str]:
    """``(opcode, offset, length)`` of each record from ``start`` to ``end`` (named
    ``end_name`` in messages), in order, up to a record of an opcode in ``stop``; the
    first damage found, as a description, ends it."""
    offset = start
    while offset < end:
        fh.seek(offset)
        head = fh.read(9)
        if len(head) < 9 or offset + 9 > end:
            yield f"the record at byte {offset} is cut short by {end_name} (byte {end})"
            return
        opcode, length = head[0], struct.unpack_from("<Q", head, 1)[0]
        if opcode in stop:
            return
        left = end - offset - 9
        if length > left:
            yield (
                f"the {_name(opcode)} at byte {offset} declares {length} bytes, but "
                f"{left} are left before {end_name}"
            )
            return
        if opcode in (_SCHEMA, _CHANNEL, _CHUNK):
            damage = _fields_damage(fh, opcode, offset, length)
            if damage:
                yield damage
                return
        yield opcode, offset, length
        if first_only:
            return
        offset += 9 + length


#: The fields of a schema and of a channel record, in order: a fixed number of bytes
#: (an int), or a length-prefixed field (its name and the size of its length).
_FIELDS: dict[int, tuple[int | tuple[str, int], ...]] = {
    _SCHEMA: (2, ("name", 4), ("encoding", 4), ("data", 4)),
    _CHANNEL: (2, 2, ("topic", 4), ("message encoding", 4), ("metadata", 4)),
    _CHUNK: (8, 8, 8, 4, ("compression", 4), ("records", 8)),
}


def _fields_damage(fh: BinaryIO, opcode: int, offset: int, length: int) -> str | None:
    """The first field of a schema, channel or chunk record that the record's length
    cannot hold (a chunk's records are not read: only its header)."""
    fh.seek(offset + 9)
    at = 0
    for field in _FIELDS[opcode]:
        if isinstance(field, int):
            at += field
            if at > length:
                return f"the {_name(opcode)} at byte {offset} ends before its fixed fields"
            fh.seek(offset + 9 + at)
            continue
        name, width = field
        raw = fh.read(width)
        if len(raw) < width or at + width > length:
            return f"the {_name(opcode)} at byte {offset} ends before its {name} field"
        declared = int.from_bytes(raw, "little")
        at += width
        if declared > length - at:
            return (
                f"the {_name(opcode)} at byte {offset}: its {name} field declares "
                f"{declared} bytes, but the record holds {length - at} after it"
            )
        at += declared
        fh.seek(offset + 9 + at)
    return None


def _name(opcode: int) -> str:
    kind = RECORD_NAMES.get(opcode)
    return f"{kind} record" if kind else f"record of unknown opcode 0x{opcode:02x}"
