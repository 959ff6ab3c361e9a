"""Choosing a reader: by file name, checked against (or else by) the content.

Rules, in order:

1. A directory is a ROS 2 bag when it holds ``metadata.yaml`` or a
   ``.db3``/``.mcap`` file; any other directory is an error.
2. An empty file is an error.
3. Binary formats are recognised by their magic bytes: ROS 1 bag
   (``#ROSBAG V2.0``), MCAP, SQLite (ROS 2 ``.db3``), zip (``.npz``).
4. Text formats (plain or gzip, whatever the name says): the name picks the
   format (``.log``/``.clf`` CARMEN, ``.dat`` CoreSLAM, ``.csv``/``.tsv``/``.txt``
   table, each optionally ``.gz``) and the first lines must look like it;
   a name that says nothing (``.gz`` alone, no or another suffix) leaves the
   choice to the content: CoreSLAM, then CARMEN, then a table of numbers.
5. Anything else is an error listing the formats.

Every failure is one :class:`~scanlines.LogFormatError` naming the file.
"""

from __future__ import annotations

from pathlib import Path

from scanlines.errors import NO_SUCH_FILE, LogFormatError
from scanlines.io.carmen_messages import looks_like_carmen
from scanlines.io.coreslam import looks_like_coreslam
from scanlines.io.rosbag_files import is_ros2_bag_dir
from scanlines.io.tabular import looks_like_table
from scanlines.io.text import read_head

__all__ = ["FORMAT_DESCRIPTIONS", "detect_format"]

#: Format name -> what it reads (for error messages and ``scanlines info``).
FORMAT_DESCRIPTIONS = {
    "carmen": "CARMEN log (.log, .clf, optionally .gz)",
    "rosbag": "ROS 1 bag (.bag), ROS 2 bag (directory, .db3, .mcap) with LaserScan",
    "coreslam": "CoreSLAM/BreezySLAM log (.dat, optionally .gz)",
    "csv": "one scan per row (.csv, optionally .gz)",
    "npz": "numpy stack of scans (.npz)",
}

_TEXT_SUFFIXES = {
    ".log": "carmen",
    ".clf": "carmen",
    ".carmen": "carmen",
    ".dat": "coreslam",
    ".csv": "csv",
    ".tsv": "csv",
    ".txt": "csv",
}
_MAGIC = (
    (b"#ROSBAG V2.0", "rosbag", (".bag",)),
    (b"\x89MCAP", "rosbag", (".mcap",)),
    (b"SQLite format 3\x00", "rosbag", (".db3",)),
    (b"PK\x03\x04", "npz", (".npz",)),
)
_SNIFFERS = {
    "coreslam": looks_like_coreslam,
    "carmen": looks_like_carmen,
    "csv": looks_like_table,
}


def _supported() -> str:
    return "; ".join(FORMAT_DESCRIPTIONS.values())


def _suffix_format(path: Path) -> str | None:
    suffixes = [s.lower() for s in path.suffixes]
    if suffixes and suffixes[-1] == ".gz":
        suffixes.pop()
    return _TEXT_SUFFIXES.get(suffixes[-1]) if suffixes else None


def detect_format(path: str | Path) -> str:
    """The format name of ``path`` (a key of :data:`FORMAT_DESCRIPTIONS`).

    Raises
    ------
    LogFormatError
        When the path is missing, empty, or of no supported format, or its
        content contradicts its name.
    """
    path = Path(path)
    if not path.exists():
        raise LogFormatError(NO_SUCH_FILE, path=path)
    if path.is_dir():
        if is_ros2_bag_dir(path):
            return "rosbag"
        raise LogFormatError(
            "a directory, but not a ROS 2 bag (no metadata.yaml, .db3 or .mcap inside)", path=path
        )
    with path.open("rb") as fh:
        magic = fh.read(16)
    if not magic:
        raise LogFormatError("the file is empty", path=path)
    for prefix, name, suffixes in _MAGIC:
        if magic.startswith(prefix):
            if path.suffix.lower() not in suffixes:
                raise LogFormatError(
                    f"the content is a {name} file ({FORMAT_DESCRIPTIONS[name]}); "
                    f"name it with the suffix {suffixes[0]} to read it",
                    path=path,
                )
            return name
    return _detect_text(path)


def _detect_text(path: Path) -> str:
    head = read_head(path)
    if not head.strip():
        raise LogFormatError("the file holds no data", path=path)
    if b"\x00" in head[:4096]:
        raise LogFormatError(
            f"binary content of an unknown format; supported: {_supported()}", path=path
        )
    named = _suffix_format(path)
    if named is not None:
        matches = looks_like_table(head, named=True) if named == "csv" else _SNIFFERS[named](head)
        if not matches:
            raise LogFormatError(
                f"the name says {FORMAT_DESCRIPTIONS[named]}, but the first record is "
                f"{_first_record(head)!r}",
                path=path,
            )
        return named
    for name, sniff in _SNIFFERS.items():
        if sniff(head):
            return name
    raise LogFormatError(
        f"unknown log format (first record {_first_record(head)!r}); supported: {_supported()}",
        path=path,
    )


def _first_record(head: bytes) -> str:
    for line in head.decode("utf-8", errors="replace").splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            return line[:60] + ("..." if len(line) > 60 else "")
    return ""
