"""Seeded mutators of bag structure: a ROS 1 bag's chunk counts, index position and
truncation inside its chunks, and NULL fields in a ROS 2 ``.db3`` database.

Like the byte mutators, each takes a ``random.Random`` and the bytes of the storage file
and returns new bytes. A mutator that finds nothing to damage returns the bytes as they
are (the input then reads cleanly).
"""

from __future__ import annotations

import random
import sqlite3
import struct
import tempfile
from pathlib import Path

from .mutate import Mutator

MAGIC = b"#ROSBAG V2.0\n"


def ros1_records(data: bytes) -> list[tuple[int, int, int, dict[str, int]]]:
    """``(offset, header length, op, {field name: offset of its value})`` of the bag's
    top-level records, as far as they can be parsed."""
    records, offset = [], len(MAGIC)
    while offset + 4 <= len(data):
        (header_length,) = struct.unpack_from("<I", data, offset)
        end = offset + 4 + header_length
        if end + 4 > len(data):
            break
        fields, pos = {}, offset + 4
        while pos + 4 <= end:
            (size,) = struct.unpack_from("<I", data, pos)
            name, sep, _ = data[pos + 4 : pos + 4 + size].partition(b"=")
            if not sep or pos + 4 + size > end:
                break
            fields[name.decode("latin-1")] = pos + 4 + len(name) + 1
            pos += 4 + size
        op_at = fields.get("op")
        if op_at is None:
            break
        (data_length,) = struct.unpack_from("<I", data, end)
        records.append((offset, header_length, data[op_at], fields))
        offset = end + 4 + data_length
    return records


def _set(data: bytes, at: int, value: bytes) -> bytes:
    return data[:at] + value + data[at + len(value) :]


def ros1_chunk_count(rng: random.Random, data: bytes) -> bytes:
    """The bag header's ``chunk_count`` lowered (to 0 at times) or raised."""
    header = next((r for r in ros1_records(data) if r[2] == 0x03), None)
    if header is None or "chunk_count" not in header[3]:
        return data
    at = header[3]["chunk_count"]
    (count,) = struct.unpack_from("<I", data, at)
    value = rng.choice([0, max(count - 1, 0), rng.randrange(count + 1), count + 1, 2**32 - 1])
    return _set(data, at, struct.pack("<I", value))


def ros1_chunk_info_count(rng: random.Random, data: bytes) -> bytes:
    """A chunk-info record's ``count`` (connections in the chunk) or one of its message
    counts set to 0, lowered or made huge."""
    infos = [r for r in ros1_records(data) if r[2] == 0x06]
    if not infos:
        return data
    offset, header_length, _, fields = rng.choice(infos)
    if rng.random() < 0.5 and "count" in fields:
        at = fields["count"]
    else:  # a message count in the record's data: (conn, count) pairs
        at = offset + 8 + header_length + 4
        if at + 4 > len(data):
            return data
    (value,) = struct.unpack_from("<I", data, at)
    new = rng.choice([0, value // 2, max(value - 1, 0), 2**31, 2**32 - 1])
    return _set(data, at, struct.pack("<I", new))


def ros1_index_pos(rng: random.Random, data: bytes) -> bytes:
    """The bag header's ``index_pos`` set to 0 (not indexed), past the end, or into a
    chunk."""
    header = next((r for r in ros1_records(data) if r[2] == 0x03), None)
    if header is None or "index_pos" not in header[3]:
        return data
    value = rng.choice([0, len(data) + rng.randrange(1, 10_000), rng.randrange(len(data)), 2**63])
    return _set(data, header[3]["index_pos"], struct.pack("<Q", value))


def ros1_truncate_in_chunks(rng: random.Random, data: bytes) -> bytes:
    """Cut inside the chunk data (what a crash while recording leaves)."""
    chunks = [r for r in ros1_records(data) if r[2] == 0x05]
    if not chunks:
        return data
    offset, header_length, _, _ = rng.choice(chunks)
    (length,) = struct.unpack_from("<I", data, offset + 4 + header_length)
    start = offset + 8 + header_length
    return data[: start + rng.randrange(max(min(length, len(data) - start), 1))]


ROS1_MUTATORS: dict[str, Mutator] = {
    "ros1_chunk_count": ros1_chunk_count,
    "ros1_chunk_info_count": ros1_chunk_info_count,
    "ros1_index_pos": ros1_index_pos,
    "ros1_truncate_in_chunks": ros1_truncate_in_chunks,
}

#: Columns of a rosbag2 ``.db3`` that may be set to NULL.
DB3_COLUMNS = {
    "topics": ("name", "type", "serialization_format", "offered_qos_profiles", "id"),
    "messages": ("topic_id", "timestamp", "data", "id"),
}


def db3_null_field(rng: random.Random, data: bytes) -> bytes:
    """One column of one (or every) row of ``topics`` or ``messages`` set to NULL, the
    table's NOT NULL constraints dropped first (as a damaged database would have it)."""
    table = rng.choice(sorted(DB3_COLUMNS))
    column = rng.choice(DB3_COLUMNS[table])
    with tempfile.TemporaryDirectory(prefix="scanlines-db3-") as folder:
        path = Path(folder) / "bag.db3"
        path.write_bytes(data)
        try:
            with sqlite3.connect(path) as db:
                row = db.execute("SELECT sql FROM sqlite_master WHERE name = ?", (table,))
                found = row.fetchone()
                if found is None:
                    return data
                ids = [r[0] for r in db.execute(f"SELECT rowid FROM {table}")]
                db.execute(f"ALTER TABLE {table} RENAME TO damaged_{table}")
                db.execute(found[0].replace("NOT NULL", "").replace("PRIMARY KEY", ""))
                db.execute(f"INSERT INTO {table} SELECT * FROM damaged_{table}")
                db.execute(f"DROP TABLE damaged_{table}")
                where = "1" if not ids or rng.random() < 0.3 else f"rowid = {rng.choice(ids)}"
                db.execute(f"UPDATE {table} SET {column} = NULL WHERE {where}")
            db.close()
        except sqlite3.Error:
            return data
        return path.read_bytes()


DB3_MUTATORS: dict[str, Mutator] = {"db3_null_field": db3_null_field}
