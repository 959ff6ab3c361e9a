"""Build ``tests/fuzz/corpus/``: inputs that once made a reader fail badly.

Run once from the repository root, then commit the files::

    python -m tests.fuzz.make_corpus

Each entry reproduces one defect of the readers as of commit 778b548 (see
``corpus/README.md``): a bug report's cases and what the fuzzer found.
``test_fuzz.py`` replays every entry through every channel. The one input too
large to commit is built at test time by :func:`build_generated`.
"""

from __future__ import annotations

import gzip
import io
import re
import shutil
import struct
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .seeds import intel_scans, robotlaser_log, write_bag

CORPUS = Path(__file__).resolve().parent / "corpus"

Builder = Callable[[Path], None]
#: Corpus file name -> builder writing it.
ENTRIES: dict[str, Builder] = {}
#: Inputs built at test time (too large to commit): name -> builder.
GENERATED: dict[str, Builder] = {}


def entry(name: str, table: dict[str, Builder] = ENTRIES) -> Callable[[Builder], Builder]:
    def register(builder: Builder) -> Builder:
        table[name] = builder
        return builder

    return register


def bag_bytes(kind: str, scans: int, workdir: Path) -> bytes:
    """The storage file of a bag of ``scans`` Intel scans (``kind``: ros1, sqlite3, mcap)."""
    return next(iter(bag_directory(kind, scans, workdir).values()))


def bag_directory(kind: str, scans: int, workdir: Path) -> dict[str, bytes]:
    """File name -> content of a bag written by the tests' bag writer."""
    target = workdir / f"bag-{kind}-{scans}"
    shutil.rmtree(target, ignore_errors=True)
    if kind == "ros1":
        write_bag(target.with_suffix(".bag"), kind, intel_scans(scans))
        content = {target.name + ".bag": target.with_suffix(".bag").read_bytes()}
        target.with_suffix(".bag").unlink()
        return content
    write_bag(target, kind, intel_scans(scans))
    files = sorted(target.iterdir(), key=lambda p: p.name == "metadata.yaml")
    content = {p.name: p.read_bytes() for p in files}  # the storage file first
    shutil.rmtree(target)
    return content


def write_directory(path: Path, files: dict[str, bytes]) -> None:
    path.mkdir()
    for name, content in files.items():
        (path / name).write_bytes(content)


def set_at(data: bytes, offset: int, value: bytes) -> bytes:
    return data[:offset] + value + data[offset + len(value) :]


# -- MCAP ---------------------------------------------------------------------------------


def mcap_summary_start(data: bytes) -> int:
    """Offset of the first summary record, from the footer (opcode 0x02) before the magic."""
    footer = data[-8 - 29 : -8]
    assert footer[0] == 0x02
    return struct.unpack_from("<Q", footer, 9)[0]


@entry("mcap_summary_length_2e62.mcap")
def mcap_summary_length_2e62(path: Path) -> None:
    data = bag_bytes("mcap", 25, path.parent)
    path.write_bytes(set_at(data, mcap_summary_start(data) + 1, struct.pack("<Q", 2**62)))


@entry("mcap_summary_length_2e64.mcap")
def mcap_summary_length_2e64(path: Path) -> None:
    data = bag_bytes("mcap", 25, path.parent)
    path.write_bytes(set_at(data, mcap_summary_start(data) + 1, struct.pack("<Q", 2**64 - 1)))


@entry("mcap_13_nuls_at_2000.mcap")
def mcap_nuls_at_2000(path: Path) -> None:
    data = bag_bytes("mcap", 25, path.parent)
    path.write_bytes(data[:2000] + b"\x00" * 13 + data[2000:])


@entry("mcap_dir_metadata_duplicate_line")
def mcap_metadata_duplicate_line(path: Path) -> None:
    files = bag_directory("mcap", 5, path.parent)
    lines = files["metadata.yaml"].split(b"\n")
    files["metadata.yaml"] = b"\n".join([lines[0], lines[1], *lines[1:]])
    write_directory(path, files)


@entry("mcap_dir_metadata_duration_two_numbers")
def mcap_metadata_two_numbers(path: Path) -> None:
    """``duration: nanoseconds: 623691000 623691000`` in ``metadata.yaml`` (TypeError)."""
    files = bag_directory("mcap", 5, path.parent)
    yaml = files["metadata.yaml"]
    files["metadata.yaml"] = re.sub(rb"(nanoseconds: )(\d+)", rb"\1\2 \2", yaml, count=1)
    write_directory(path, files)


def with_metadata_count(value: bytes) -> Builder:
    """A 5-scan MCAP bag whose ``metadata.yaml`` gives the topic's ``message_count: value``."""

    def build(path: Path) -> None:
        files = bag_directory("mcap", 5, path.parent)
        yaml = files["metadata.yaml"]
        at = yaml.rindex(b"message_count: 5")
        files["metadata.yaml"] = yaml[:at] + b"message_count: " + value + yaml[at + 16 :]
        write_directory(path, files)

    return build


entry("mcap_dir_metadata_count_empty")(with_metadata_count(b""))
entry("mcap_dir_metadata_count_text")(with_metadata_count(b"5 5 5"))
entry("mcap_dir_metadata_count_zero")(with_metadata_count(b"0"))


# -- ROS 2 sqlite3 ------------------------------------------------------------------------


def flipped(data: bytes, offset: int, bit: int) -> bytes:
    return set_at(data, offset, bytes([data[offset] ^ bit]))


@entry("db3_dir_definition_bit_flip")
def db3_definition_bit_flip(path: Path) -> None:
    files = bag_directory("sqlite3", 5, path.parent)
    storage = next(iter(files))
    definition = files[storage].index(b"float32 angle_min")
    files[storage] = flipped(files[storage], definition + 3, 0x01)  # float32 -> flo`t32
    write_directory(path, files)


@entry("db3_dir_topic_row_bit_flip")
def db3_topic_row_bit_flip(path: Path) -> None:
    """A bit flipped in the record header of the ``topics`` row (TypeError)."""
    files = bag_directory("sqlite3", 5, path.parent)
    storage = next(iter(files))
    row = files[storage].index(b"/scansensor_msgs/msg/LaserScan")
    files[storage] = flipped(files[storage], row - 9, 0x01)
    write_directory(path, files)


@entry("db3_dir_topic_name_bit_flip")
def db3_topic_name_bit_flip(path: Path) -> None:
    """The topic renamed in the database but not in ``metadata.yaml`` (silent loss)."""
    files = bag_directory("sqlite3", 5, path.parent)
    storage = next(iter(files))
    row = files[storage].index(b"/scansensor_msgs/msg/LaserScan")
    files[storage] = flipped(files[storage], row + 1, 0x01)
    write_directory(path, files)


# -- ROS 1 --------------------------------------------------------------------------------


def ros1_records(data: bytes) -> list[tuple[int, int, int]]:
    """``(offset, header length, op code)`` of each top-level record of a ROS 1 bag."""
    records, offset = [], len(b"#ROSBAG V2.0\n")
    while offset < len(data):
        header_length = struct.unpack_from("<I", data, offset)[0]
        header = data[offset + 4 : offset + 4 + header_length]
        op = header[header.index(b"op=") + 3]
        data_length = struct.unpack_from("<I", data, offset + 4 + header_length)[0]
        records.append((offset, header_length, op))
        offset += 8 + header_length + data_length
    return records


def ros1_data_length_offset(data: bytes, op: int) -> int:
    offset, header_length, _ = next(r for r in ros1_records(data) if r[2] == op)
    return offset + 4 + header_length


@entry("ros1_index_data_length_7.bag")
def ros1_damaged_index(path: Path) -> None:
    """The data length of the index-data record (op 0x04) set to 7 (AssertionError)."""
    data = bag_bytes("ros1", 20, path.parent)
    path.write_bytes(set_at(data, ros1_data_length_offset(data, 0x04), struct.pack("<I", 7)))


@entry("ros1_chunk_data_length_2e31.bag")
def ros1_huge_chunk(path: Path) -> None:
    """The data length of the chunk record (op 0x05) set to 2^31 (struct.error)."""
    data = bag_bytes("ros1", 20, path.parent)
    offset = ros1_data_length_offset(data, 0x05)
    path.write_bytes(set_at(data, offset, struct.pack("<I", 2**31)))


@entry("ros1_definition_zeroed.bag")
def ros1_definition_zeroed(path: Path) -> None:
    """16 NUL bytes in the connection's message definition (a multi-line error)."""
    data = bag_bytes("ros1", 20, path.parent)
    at = data.rindex(b"float32 angle_increment")
    path.write_bytes(set_at(data, at, b"\x00" * 16))


@entry("ros1_range_signaling_nan.bag")
def ros1_range_signaling_nan(path: Path) -> None:
    """One range of the first scan set to the float32 signaling NaN 0x7f800001 (its widening
    to float64 warns)."""
    data = bag_bytes("ros1", 5, path.parent)
    ranges = np.asarray(intel_scans(1)[0].ranges[:4], dtype=np.float32).tobytes()
    path.write_bytes(set_at(data, data.index(ranges), struct.pack("<I", 0x7F800001)))


def ros1_header_field(data: bytes, name: str) -> int:
    """The offset of the value of the bag header's field ``name``."""
    offset, header_length, _ = ros1_records(data)[0]
    return data.index(name.encode() + b"=", offset, offset + 4 + header_length) + len(name) + 1


@entry("ros1_chunk_count_zero.bag")
def ros1_chunk_count_zero(path: Path) -> None:
    """The bag header's ``chunk_count`` set to 0 (silent loss: 0 scans of 20, exit 0)."""
    data = bag_bytes("ros1", 20, path.parent)
    path.write_bytes(set_at(data, ros1_header_field(data, "chunk_count"), struct.pack("<I", 0)))


@entry("ros1_chunk_info_count_zero.bag")
def ros1_chunk_info_count_zero(path: Path) -> None:
    """The chunk-info record's ``count`` set to 0 (silent loss: 0 scans of 20, exit 0)."""
    data = bag_bytes("ros1", 20, path.parent)
    offset, header_length, _ = next(r for r in ros1_records(data) if r[2] == 0x06)
    at = data.index(b"count=", offset, offset + 4 + header_length) + len(b"count=")
    path.write_bytes(set_at(data, at, struct.pack("<I", 0)))


@entry("ros1_truncated_in_chunk.bag")
def ros1_truncated_in_chunk(path: Path) -> None:
    """The bag cut 20,000 bytes into its chunk, before the index (a crash while recording):
    refused even with ``--on-error skip``."""
    data = bag_bytes("ros1", 20, path.parent)
    offset, header_length, _ = next(r for r in ros1_records(data) if r[2] == 0x05)
    path.write_bytes(data[: offset + 8 + header_length + 20_000])


@entry("db3_dir_topic_name_null")
def db3_topic_name_null(path: Path) -> None:
    """A ``.db3`` (no ``metadata.yaml``) with /scan and /notes, the name of /notes NULL
    (``info``: TypeError sorting the topics)."""
    import sqlite3

    write_bag(path, "sqlite3", intel_scans(5), string_topic="/notes")
    (path / "metadata.yaml").unlink()
    database = next(path.glob("*.db3"))
    with sqlite3.connect(database) as db:
        (sql,) = db.execute("SELECT sql FROM sqlite_master WHERE name = 'topics'").fetchone()
        db.execute("ALTER TABLE topics RENAME TO old_topics")
        db.execute(sql.replace("NOT NULL", ""))
        db.execute("INSERT INTO topics SELECT * FROM old_topics")
        db.execute("DROP TABLE old_topics")
        db.execute("UPDATE topics SET name = NULL WHERE name = '/notes'")
    db.close()


# -- NPZ ----------------------------------------------------------------------------------


def npz_bytes(compressed: bool = False, **arrays: object) -> bytes:
    buffer = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buffer, **arrays)
    return buffer.getvalue()


def stack(**changes: object) -> bytes:
    """A 5 x 10 stack of 2 m ranges, with ``changes`` to its keys."""
    arrays = {"ranges": np.full((5, 10), 2.0), "angle_min": 0.0, "angle_increment": 0.001}
    return npz_bytes(**(arrays | changes))


@entry("npz_flipped_data_byte.npz")
def npz_flipped_data_byte(path: Path) -> None:
    """The bug report's 100 x 1000 case, 20 times smaller: a CRC error mid-stream."""
    data = npz_bytes(ranges=np.full((100, 50), 2.0), angle_min=0.0, angle_increment=0.001)
    path.write_bytes(flipped(data, 20_000, 0x01))


@entry("npz_compressed_flipped_byte.npz")
def npz_compressed_flipped_byte(path: Path) -> None:
    """A bit flipped in the deflate stream of ``ranges.npy`` (zlib.error)."""
    ranges = np.random.default_rng(0).uniform(1, 9, (20, 50))
    data = npz_bytes(True, ranges=ranges, angle_min=0.0, angle_increment=0.001)
    path.write_bytes(flipped(data, 100, 0x01))


@entry("npz_header_missing_brace.npz")
def npz_header_missing_brace(path: Path) -> None:
    with zipfile.ZipFile(io.BytesIO(stack())) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    npy = members["ranges.npy"]
    length = int.from_bytes(npy[8:10], "little")
    header = npy[10 : 10 + length].replace(b"}", b" ")
    members["ranges.npy"] = npy[:10] + header + npy[10 + length :]
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, content in members.items():
            archive.writestr(name, content)
    path.write_bytes(buffer.getvalue())


@entry("npz_member_name_with_cr.npz")
def npz_member_name_with_cr(path: Path) -> None:
    """A carriage return in a name of the zip's central directory (a multi-line error)."""
    data = stack(timestamps=np.arange(5.0))
    central = data.rindex(b"timestamps.npy")
    path.write_bytes(set_at(data, central + 4, b"\r"))


NPZ_ODD_ARRAYS: dict[str, dict[str, object]] = {
    "npz_angle_increment_text.npz": {"angle_increment": "abc"},
    "npz_angle_increment_complex.npz": {"angle_increment": 0.001 + 1j},
    "npz_timestamps_complex.npz": {"timestamps": np.arange(5) + 1j},
    "npz_timestamps_datetime.npz": {"timestamps": np.zeros(5, dtype="datetime64[s]")},
    "npz_poses_text.npz": {"poses": np.full((5, 3), "abc")},
    "npz_ranges_structured.npz": {"ranges": np.zeros((5, 10), dtype=[("x", "<f4"), ("y", "<i4")])},
    "npz_ranges_text.npz": {"ranges": np.full((5, 10), "abc")},
    "npz_ranges_void.npz": {"ranges": np.zeros((5, 10), dtype="V3")},
    "npz_range_max_1e308.npz": {"range_max": 1e308},
    "npz_angle_min_1e308.npz": {"angle_min": 1e308},
}
for _name, _changes in NPZ_ODD_ARRAYS.items():
    entry(_name)(lambda path, changes=_changes: path.write_bytes(stack(**changes)))

# -- CARMEN -------------------------------------------------------------------------------


@entry("carmen_robotlaser_stamp_3e9.log")
def carmen_robotlaser_stamp_3e9(path: Path) -> None:
    """Valid to read; ``run --out x.mcap`` fails in the bag writer (struct.error)."""
    scans = intel_scans(3)
    text = robotlaser_log(scans)
    for scan in scans:
        text = text.replace(f"{scan.timestamp:.6f}", "3000000000.000000")
    path.write_text(text)


def flaser_line(beams: int) -> bytes:
    return b"FLASER %d " % beams + b"1 " * beams + b"0 0 0 0 0 0 1.0 host 1.0\n"


@entry("carmen_flaser_13m_beams.log.gz")
def carmen_flaser_13m_beams(path: Path) -> None:
    """One ``FLASER`` line of 13.4 million beams (27 MB of text)."""
    path.write_bytes(gzip.compress(flaser_line(13_400_000), compresslevel=9, mtime=0))


@entry("carmen_flaser_256mb_line.log.gz", GENERATED)
def carmen_flaser_256mb_line(path: Path) -> None:
    """One ``FLASER`` line of 256 MB (134 million beams), written in pieces."""
    beams = 2**27
    with gzip.GzipFile(path, "wb", compresslevel=6, mtime=0) as fh:
        fh.write(b"FLASER %d " % beams)
        for _ in range(beams // 2**20):
            fh.write(b"1 " * 2**20)
        fh.write(b"0 0 0 0 0 0 1.0 host 1.0\n")


# -- the files that set things (built at test time: each beside a CARMEN excerpt) ----------


def settings_input(path: Path, name: str, text: str, scans: int = 3) -> None:
    """A settings-file input (``file_target.py``): ``name`` holding ``text`` beside an
    excerpt of ``scans`` scans of the Intel sample."""
    from .seeds import carmen_excerpt

    path.mkdir(parents=True)
    (path / name).write_text(text)
    (path / "log.clf").write_text(carmen_excerpt("intel", scans))


def alias_bomb_yaml(levels: int = 8) -> str:
    rows = ['    a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    names = "abcdefghij"
    for k in range(1, levels):
        rows.append(f"    {names[k]}: &{names[k]} [{','.join(['*' + names[k - 1]] * 9)}]")
    tail = f"scanlines:\n  ros__parameters:\n    min_points: *{names[levels - 1]}\n"
    return "other:\n  ros__parameters:\n" + "\n".join(rows) + "\n" + tail


PARAMS = "scanlines:\n  ros__parameters:\n"
SETTINGS_ENTRIES = {
    "params_alias_bomb": ("params.yaml", alias_bomb_yaml()),
    "params_recursive_alias": ("params.yaml", "scanlines:\n  ros__parameters: &a\n    n: *a\n"),
    "params_nested_100kb": ("params.yaml", PARAMS + "    k: " + "[" * 100_000 + "\n"),
    "params_integer_5000_digits": ("params.yaml", PARAMS + "    min_points: " + "1" * 5000),
    "config_nested_arrays": ("config.toml", "[params]\nmin_points = " + "[" * 100_000),
    "profile_nested": ("profile.json", "[" * 100_000 + "]" * 100_000),
    "profile_integer_5000_digits": (
        "profile.json",
        '{"format": "scanlines-sensor-profile/1", "noise_sigma0": ' + "1" * 5000 + "}",
    ),
}
for _name, (_file, _text) in SETTINGS_ENTRIES.items():
    entry(_name, GENERATED)(lambda path, f=_file, t=_text: settings_input(path, f, t))


def map_input(path: Path, change: Callable[[dict], None] | None, raw: str | None = None) -> None:
    """A line-map input: the map of the Intel excerpt's first 20 scans, changed."""
    import json

    from scanlines.map import build_map
    from scanlines.map.export import write_map

    scans = intel_scans(20)
    settings_input(path, "initial.txt", "{!r},{!r},{!r},{!r}\n".format(
        scans[0].timestamp, *scans[0].pose), scans=20)  # fmt: skip
    write_map(build_map(enumerate(scans)).line_map.lines(), path / "map.json", overwrite=True)
    document = json.loads((path / "map.json").read_text())
    if change is not None:
        change(document)
    text = json.dumps(document)
    (path / "map.json").write_text(text if raw is None else text.replace('"@raw@"', raw, 1))


MAP_ENTRIES: dict[str, tuple[Callable[[dict], None] | None, str | None]] = {
    "map_ends_1e308": (lambda m: m["lines"][0].update(start=[1e308, 1e308]), None),
    "map_origin_nan": (lambda m: m["frame"].update(origin=[float("nan"), 0.0]), None),
    "map_rho_digits": (lambda m: m["lines"][0].update(rho="@raw@"), "9" * 4301),
    "map_nested_covariance": (lambda m: m["lines"][0].update(covariance="@raw@"), "[" * 10**5),
}
for _name, (_change, _raw) in MAP_ENTRIES.items():
    entry(_name, GENERATED)(lambda path, c=_change, r=_raw: map_input(path, c, r))


# -- building -----------------------------------------------------------------------------


def build(folder: Path, entries: dict[str, Builder]) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, builder in entries.items():
        path = folder / name
        shutil.rmtree(path, ignore_errors=True)
        path.unlink(missing_ok=True)
        builder(path)
        paths.append(path)
    return paths


def build_generated(folder: Path) -> list[Path]:
    """The corpus inputs too large to commit, written into ``folder``."""
    return build(folder, GENERATED)


def corpus_inputs() -> list[Path]:
    """Every committed corpus input (files and bag directories), sorted."""
    return sorted(p for p in CORPUS.iterdir() if p.name != "README.md")


if __name__ == "__main__":
    for built in build(CORPUS, ENTRIES):
        size = sum(f.stat().st_size for f in ([built] if built.is_file() else built.iterdir()))
        print(f"{size:8d}  {built.name}")
