"""A ROS 1 bag (format 2.0) read by its data: the chunks and what they hold.

A bag's index (the bag header's ``chunk_count``, the chunk-info records at
``index_pos``) says where its messages are; a damaged or stale index (a
lowered ``chunk_count``, a zeroed chunk-info ``count``, a bag cut short by a
crash while recording, before its index was written) hides some of them.
:func:`walk` reads the file from its first record to its end, as ``rosbag
reindex`` does: every chunk record, and inside each chunk the connection
(op 0x07) and message data (op 0x02) records, counting the messages of each
connection. :func:`messages` then yields them in file order.

Every length field is checked against what is left of the file (or of the
chunk) before anything is read, so a damaged length is reported as damage at
its byte offset, never as a huge allocation. The first damage (or the end of a
truncated file) ends the walk; what it held before is kept.
"""

from __future__ import annotations

import bz2
import struct
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import BinaryIO

__all__ = ["BagDamage", "Ros1Connection", "Ros1Layout", "messages", "walk"]

MAGIC = b"#ROSBAG V2.0\n"
OP_MESSAGE, OP_BAG_HEADER, OP_INDEX_DATA, OP_CHUNK, OP_CHUNK_INFO, OP_CONNECTION = 2, 3, 4, 5, 6, 7
#: Longest record header accepted (a real one is well under a kilobyte).
MAX_HEADER_BYTES = 1 << 20
_U32 = struct.Struct("<I")


@dataclass(frozen=True)
class BagDamage:
    """Where the walk stopped: the byte offset in the file, what is wrong, and whether
    the file simply ends there (``truncated``)."""

    offset: int
    reason: str
    truncated: bool

    def describe(self) -> str:
        if self.truncated:
            return f"the bag is truncated at byte {self.offset} ({self.reason})"
        return f"the bag is damaged at byte {self.offset} ({self.reason})"


@dataclass(frozen=True)
class Ros1Connection:
    """A connection record: its id, topic, message type (ROS 2 style name), md5 and
    message definition."""

    id: int
    topic: str
    msgtype: str
    md5sum: str
    msgdef: str


@dataclass(frozen=True)
class _Chunk:
    offset: int
    compression: str
    size: int  # uncompressed size the header declares
    data_offset: int
    data_length: int  # clipped to the file
    short: bool  # the file ends inside it


@dataclass
class Ros1Layout:
    """What :func:`walk` found.

    ``counts`` counts the messages of each connection id in the chunks;
    ``damage`` is the first damage (``None`` for a sound file); ``index_damage``
    is damage found only in the index section, after the last chunk (the data is
    whole, the index is not); ``index_pos`` is the bag header's.
    """

    size: int
    index_pos: int = 0
    chunk_count: int = 0
    connections: dict[int, Ros1Connection] = field(default_factory=dict)
    chunks: list[_Chunk] = field(default_factory=list)
    counts: Counter[int] = field(default_factory=Counter)
    damage: BagDamage | None = None
    damage_chunk: int = -1  # the damage comes after this chunk (or in it)
    index_damage: BagDamage | None = None
    index_counts: Counter[int] = field(default_factory=Counter)
    chunk_positions: list[int] = field(default_factory=list)

    def topic_counts(self, counts: Counter[int] | None = None) -> dict[str, tuple[str, int]]:
        """Topic -> (message type, messages the chunks hold, or ``counts`` gives)."""
        counts = self.counts if counts is None else counts
        table: dict[str, tuple[str, int]] = {}
        for conn in self.connections.values():
            msgtype, count = table.get(conn.topic, (conn.msgtype, 0))
            table[conn.topic] = (msgtype, count + counts[conn.id])
        return table


class _Damage(Exception):
    def __init__(self, offset: int, reason: str, truncated: bool = False) -> None:
        super().__init__(reason)
        self.damage = BagDamage(offset, reason, truncated)


def _fields(raw: bytes, offset: int) -> dict[str, bytes]:
    """The ``name=value`` fields of a record header that starts at file byte ``offset``."""
    fields: dict[str, bytes] = {}
    pos = 0
    while pos < len(raw):
        if pos + 4 > len(raw):
            raise _Damage(offset + pos, "a header field length is cut short")
        (length,) = _U32.unpack_from(raw, pos)
        if length > len(raw) - pos - 4:
            raise _Damage(
                offset + pos,
                f"a header field length of {length} bytes runs past its header",
            )
        name, sep, value = raw[pos + 4 : pos + 4 + length].partition(b"=")
        if not sep:
            raise _Damage(offset + pos, "a header field without '='")
        fields[name.decode("latin-1")] = value
        pos += 4 + length
    return fields


@dataclass(frozen=True)
class _Record:
    offset: int
    op: int
    fields: dict[str, bytes]
    data_offset: int
    data_length: int
    declared_length: int


def _read_record(
    fh: BinaryIO, offset: int, end: int, base: int, *, clip: bool = False, at_end: bool = False
) -> _Record:
    """The record at ``offset`` of ``fh`` (its data not read); ``end`` bounds it, ``base``
    turns an offset of ``fh`` into a file offset. With ``clip``, data running past ``end``
    is cut there (``data_length < declared_length``) rather than damage. ``at_end``: ``end``
    is where a truncated file ends, so a record cut short there is truncation."""
    fh.seek(offset)
    left = end - offset
    if left < 4:
        raise _Damage(base + offset, "a record header length is cut short", truncated=at_end)
    (header_length,) = _U32.unpack(fh.read(4))
    if header_length > left - 4:
        raise _Damage(
            base + offset,
            f"a record header length of {header_length} bytes runs past the end "
            f"({left - 4} bytes left)",
            truncated=at_end and header_length <= MAX_HEADER_BYTES,
        )
    if header_length > MAX_HEADER_BYTES:
        raise _Damage(base + offset, f"a record header length of {header_length} bytes")
    fields = _fields(fh.read(header_length), base + offset + 4)
    op_field = fields.get("op")
    if op_field is None or len(op_field) != 1:
        raise _Damage(base + offset, "a record header without its op field")
    if left - 4 - header_length < 4:
        raise _Damage(base + offset, "a record data length is cut short", truncated=at_end)
    (data_length,) = _U32.unpack(fh.read(4))
    data_offset = offset + 8 + header_length
    if data_length > end - data_offset and clip:
        return _Record(offset, op_field[0], fields, data_offset, end - data_offset, data_length)
    if data_length > end - data_offset:
        raise _Damage(
            base + offset + 4 + header_length,
            f"a data length of {data_length} bytes runs past the end "
            f"({end - data_offset} bytes left)",
            truncated=at_end,
        )
    return _Record(offset, op_field[0], fields, data_offset, data_length, data_length)


def _u32(record: _Record, name: str, base: int) -> int:
    value = record.fields.get(name)
    if value is None or len(value) != 4:
        raise _Damage(base + record.offset, f"the {name} field of an op {record.op:#04x} record")
    return _U32.unpack(value)[0]


def _text(record: _Record, name: str, base: int) -> str:
    value = record.fields.get(name)
    if value is None:
        raise _Damage(base + record.offset, f"no {name} field in an op {record.op:#04x} record")
    try:
        return value.decode()
    except UnicodeDecodeError:
        raise _Damage(base + record.offset, f"the {name} field is not UTF-8") from None


def _connection(fh: BinaryIO, record: _Record, base: int) -> Ros1Connection:
    conn = _u32(record, "conn", base)
    topic = _text(record, "topic", base)
    if topic:  # as rosbags names it: no empty parts (//scan/ -> /scan)
        topic = "/" * topic.startswith("/") + "/".join(part for part in topic.split("/") if part)
    fh.seek(record.data_offset)
    details = _fields(fh.read(record.data_length), base + record.data_offset)
    info = _Record(record.offset, record.op, details, 0, 0, 0)
    msgtype = _text(info, "type", base)
    name = msgtype.split("/")
    if len(name) == 2:  # ROS 1 names (sensor_msgs/LaserScan) as rosbags names them
        msgtype = f"{name[0]}/msg/{name[1]}"
    return Ros1Connection(
        conn,
        topic,
        msgtype,
        _text(info, "md5sum", base) if "md5sum" in details else "",
        _text(info, "message_definition", base) if "message_definition" in details else "",
    )


def walk(path: Path, *, inside: bool = False) -> Ros1Layout:
    """Read the bag at ``path`` by its records (see the module docstring). Raises
    ``OSError`` only; a file that is not a ROS 1 bag 2.0 at all has its damage at byte 0.

    After damage between chunks the walk goes on at the next chunk the index places
    after it; after damage inside a chunk, at the chunk's end. Only the first damage is
    kept (``damage``, with ``damage_chunk``: the chunk it is in or before).

    The messages of a chunk are counted by the index-data records after it when the bag
    has an index (cheap: damage inside the chunk is then met while reading it), else,
    or with ``inside``, by walking the chunk's records."""
    size = path.stat().st_size
    layout = Ros1Layout(size)
    with path.open("rb") as fh:
        if fh.read(len(MAGIC)) != MAGIC:
            layout.damage = BagDamage(0, "no '#ROSBAG V2.0' line", size < len(MAGIC))
            return layout
        offset = len(MAGIC)
        try:
            header = _read_record(fh, offset, size, 0)
            if header.op != OP_BAG_HEADER:
                raise _Damage(offset, "the first record is not the bag header")
        except _Damage as damage:
            layout.damage = damage.damage
            return layout
        layout.index_pos = int.from_bytes(header.fields.get("index_pos", b"")[:8], "little")
        layout.chunk_count = int.from_bytes(header.fields.get("chunk_count", b"")[:4], "little")
        offset = header.data_offset + header.data_length
        indexed = offset < layout.index_pos < size and _is_index(fh, layout.index_pos, size)
        if indexed:
            _read_index(fh, layout)
        elif layout.index_pos:
            layout.index_damage = BagDamage(
                min(layout.index_pos, size),
                f"{_NO_INDEX} {layout.index_pos} points at no index record",
                layout.index_pos >= size,
            )
        end = layout.index_pos if indexed else size
        counting = _Counting(fh, layout, by_index_data=indexed and not inside)
        try:
            _walk_records(fh, layout, offset, end, indexed, counting)
        finally:
            counting.finish()
    return layout


def _walk_records(
    fh: BinaryIO, layout: Ros1Layout, offset: int, end: int, indexed: bool, counting: _Counting
) -> None:
    """The records from ``offset`` to ``end`` (the index, or the end of the file)."""
    while offset < end:
        try:
            record = _read_record(fh, offset, end, 0, clip=not indexed, at_end=not indexed)
        except _Damage as damage:
            if _note(layout, damage.damage):
                break
            later = [p for p in layout.chunk_positions if p > offset]
            if not later:
                break
            offset = min(later)
            continue
        if record.op == OP_CHUNK:
            try:
                counting.chunk(record)
            except _Damage as damage:
                if _note(layout, damage.damage):
                    break
            if record.data_length < record.declared_length:
                _note(
                    layout,
                    BagDamage(
                        offset,
                        f"the file ends {record.data_length} bytes into a chunk of "
                        f"{record.declared_length}",
                        True,
                    ),
                )
                break
        elif record.op == OP_CONNECTION:
            try:
                connection = _connection(fh, record, 0)
            except _Damage as damage:
                _note(layout, damage.damage)
                break
            layout.connections.setdefault(connection.id, connection)
        elif record.op == OP_INDEX_DATA:
            counting.index_data(record)
        elif record.op != OP_CHUNK_INFO:
            if _note(
                layout,
                BagDamage(offset, f"a record of unknown op {record.op:#04x}", False),
            ):
                break
        elif record.data_length < record.declared_length:
            _note(layout, BagDamage(offset, "the file ends inside a record", True))
            break
        offset = record.data_offset + record.data_length


class _Counting:
    """Counts the messages of each chunk: in an indexed bag by the index-data records
    (op 0x04) written after the chunk, one per connection (as many records as the chunk
    holds, at most: ``count`` is bounded by the record's length); else, or for a chunk
    without them, by walking the chunk's own records."""

    def __init__(self, fh: BinaryIO, layout: Ros1Layout, *, by_index_data: bool) -> None:
        self.fh, self.layout, self.by_index_data = fh, layout, by_index_data
        self.pending: _Chunk | None = None
        self.counts: Counter[int] = Counter()

    def chunk(self, record: _Record) -> None:
        self.finish()
        compression = _text(record, "compression", 0)
        size = _u32(record, "size", 0)
        short = record.data_length < record.declared_length
        chunk = _Chunk(
            record.offset, compression, size, record.data_offset, record.data_length, short
        )
        self.layout.chunks.append(chunk)
        if self.by_index_data and not short:
            self.pending, self.counts = chunk, Counter()
        else:
            _count_inside(self.fh, chunk, self.layout)

    def index_data(self, record: _Record) -> None:
        if self.pending is None:
            return
        conn, count = record.fields.get("conn", b""), record.fields.get("count", b"")
        if len(conn) == 4 and len(count) == 4:
            most = record.data_length // 12  # (time, offset) entries of 12 bytes
            self.counts[_U32.unpack(conn)[0]] += min(_U32.unpack(count)[0], most)

    def finish(self) -> None:
        """Settle the pending chunk: its index-data counts, or a walk of its records."""
        chunk, self.pending = self.pending, None
        if chunk is None:
            return
        if self.counts:
            self.layout.counts.update(self.counts)
            return
        try:
            _count_inside(self.fh, chunk, self.layout)
        except _Damage as damage:
            _note(self.layout, damage.damage)


_NO_INDEX = "the bag header's index_pos"


def _is_index(fh: BinaryIO, offset: int, size: int) -> bool:
    """Whether a connection or chunk-info record (the index section) starts at ``offset``."""
    try:
        return _read_record(fh, offset, size, 0).op in (OP_CONNECTION, OP_CHUNK_INFO)
    except _Damage:
        return False


def _note(layout: Ros1Layout, damage: BagDamage) -> bool:
    """Keep ``damage`` (after the chunks walked so far) if it is the first; damage in
    the index section (from ``index_pos`` on) is ``index_damage``. True: stop the walk
    (the file ends there)."""
    last = layout.chunks[-1] if layout.chunks else None
    data_end = last.data_offset + last.data_length if last else 0
    if 0 < layout.index_pos <= damage.offset and data_end <= layout.index_pos:
        # past the last chunk, where the index starts: the data is whole
        if layout.index_damage is None or layout.index_damage.reason.startswith(_NO_INDEX):
            layout.index_damage = damage
        return True
    if layout.damage is None:
        layout.damage = damage
        layout.damage_chunk = len(layout.chunks) - 1
    return damage.truncated


def _read_index(fh: BinaryIO, layout: Ros1Layout) -> None:
    """The index section from ``index_pos``: connections, chunk places and the message
    counts its chunk-info records list (all of them, whatever ``chunk_count`` says)."""
    offset = layout.index_pos
    try:
        while offset < layout.size:
            record = _read_record(fh, offset, layout.size, 0)
            if record.op == OP_CONNECTION:
                connection = _connection(fh, record, 0)
                layout.connections.setdefault(connection.id, connection)
            elif record.op == OP_CHUNK_INFO:
                position = record.fields.get("chunk_pos", b"")
                if len(position) == 8:
                    layout.chunk_positions.append(int.from_bytes(position, "little"))
                fh.seek(record.data_offset)
                pairs = fh.read(record.data_length)
                for k in range(0, len(pairs) - 7, 8):
                    conn, count = struct.unpack_from("<II", pairs, k)
                    layout.index_counts[conn] += count
            offset = record.data_offset + record.data_length
    except _Damage as damage:
        layout.index_damage = damage.damage


def _chunk_data(fh: BinaryIO, chunk: _Chunk) -> tuple[BinaryIO, int, int]:
    """The chunk's records as ``(stream, start, end)``: the file itself for an
    uncompressed chunk, the decompressed bytes otherwise."""
    if chunk.compression == "none":
        return fh, chunk.data_offset, chunk.data_offset + chunk.data_length
    fh.seek(chunk.data_offset)
    packed = fh.read(chunk.data_length)
    try:
        if chunk.compression == "bz2":
            data = bz2.BZ2Decompressor().decompress(packed, max_length=chunk.size)
        elif chunk.compression == "lz4":
            from lz4.frame import LZ4FrameDecompressor

            data = LZ4FrameDecompressor().decompress(packed, max_length=chunk.size)
        else:
            raise _Damage(chunk.offset, f"a chunk of unknown compression {chunk.compression!r}")
    except (OSError, ValueError, RuntimeError, EOFError) as exc:
        reason = f"a {chunk.compression} chunk cannot be decompressed: {exc}"
        raise _Damage(chunk.offset, reason) from None
    return BytesIO(data), 0, len(data)


def _inner(
    fh: BinaryIO, chunk: _Chunk, layout: Ros1Layout | None
) -> Iterator[tuple[_Record, BinaryIO]]:
    """The message records of a chunk with the stream holding their data (and, with
    ``layout``, its connections noted there); damage inside raises :class:`_Damage`."""
    stream, start, end = _chunk_data(fh, chunk)
    base = 0 if stream is fh else chunk.data_offset
    offset = start
    while offset < end:
        record = _read_record(stream, offset, end, base, at_end=chunk.short)
        if record.op == OP_CONNECTION:
            if layout is not None:
                connection = _connection(stream, record, base)
                layout.connections.setdefault(connection.id, connection)
        elif record.op == OP_MESSAGE:
            yield record, stream
        else:
            raise _Damage(base + offset, f"a record of op {record.op:#04x} inside a chunk")
        offset = record.data_offset + record.data_length


def _count_inside(fh: BinaryIO, chunk: _Chunk, layout: Ros1Layout) -> None:
    """Count the chunk's messages (and note its connections) by walking its records."""
    for message, _ in _inner(fh, chunk, layout):
        layout.counts[_u32(message, "conn", 0)] += 1


def messages(
    path: Path, layout: Ros1Layout, connection_ids: set[int]
) -> Iterator[tuple[int, int, bytes] | BagDamage]:
    """``(connection id, receive time in ns, serialized message)`` of the connections
    ``connection_ids``, in file order, from the chunks :func:`walk` found; a
    :class:`BagDamage` where damage is (the walk's first, and any it did not look for
    inside a chunk it counted by its index data). The caller reports them."""
    known = layout.damage
    with path.open("rb") as fh:
        if known is not None and layout.damage_chunk < 0:
            yield known
        for number, chunk in enumerate(layout.chunks):
            try:
                for record, stream in _inner(fh, chunk, None):
                    conn = _u32(record, "conn", 0)
                    if conn not in connection_ids:
                        continue
                    time = record.fields.get("time")
                    if time is None or len(time) != 8:
                        raise _Damage(record.offset, "the time field of a message record")
                    sec, nsec = struct.unpack("<II", time)
                    stream.seek(record.data_offset)
                    payload = stream.read(record.data_length)
                    yield conn, sec * 1_000_000_000 + nsec, payload
            except _Damage as damage:
                if known is None or damage.damage.offset != known.offset:
                    yield damage.damage
            if known is not None and number == layout.damage_chunk:
                yield known
