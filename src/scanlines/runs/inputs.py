"""The logs a fleet run reads: its inputs as log files, a name for each, their size in records."""

from __future__ import annotations

import glob
from collections.abc import Iterable, Sequence
from pathlib import Path

from scanlines.errors import ParameterError
from scanlines.reader_options import ReaderOptions

#: Suffixes of the log files a folder given as input is searched for.
LOG_SUFFIXES = (".log", ".clf", ".gz", ".dat", ".csv", ".npz", ".bag", ".mcap", ".db3")


def expand_inputs(inputs: Iterable[str | Path]) -> list[Path]:
    """Files, folders (searched for logs, ROS 2 bag folders kept whole) and glob patterns,
    in a stable order without duplicates."""
    found: list[Path] = []
    for item in inputs:
        text = str(item)
        matches = sorted(glob.glob(text)) if any(c in text for c in "*?[") else [text]
        if not matches:
            raise ParameterError(f"no log matches {text!r}")
        for match in map(Path, matches):
            if match.is_dir() and not _is_bag_folder(match):
                found += _logs_in(match)
            else:
                found.append(match)
    return list(dict.fromkeys(p.resolve() for p in found))


def _logs_in(folder: Path) -> list[Path]:
    """The logs under ``folder``: files with a log suffix, ROS 2 bag folders whole; hidden
    files and folders (temporary outputs) left out."""
    found: list[Path] = []
    for child in sorted(folder.iterdir()):
        if child.name.startswith("."):
            continue
        if child.is_dir():
            found += [child] if _is_bag_folder(child) else _logs_in(child)
        elif child.suffix.lower() in LOG_SUFFIXES:
            found.append(child)
    return found


def _is_bag_folder(path: Path) -> bool:
    """A ROS 2 bag folder (with its ``metadata.yaml``); other folders are searched."""
    return (path / "metadata.yaml").exists()


def log_names(paths: Sequence[Path]) -> list[str]:
    """A unique name per log: its file name, with as many parent folders as it takes to
    tell equal names apart (joined by ``__``)."""
    depth = 1
    while True:
        names = ["__".join(p.parts[-depth:]) for p in paths]
        if len(set(names)) == len(names) or depth > max(len(p.parts) for p in paths):
            return [_safe(name) for name in names]
        depth += 1


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in name)


def estimated_records(path: Path, reader_options: ReaderOptions) -> int:
    """About how many scan records a log holds, cheaply (the last chunk is open-ended, so
    this only decides how a log is split)."""
    from scanlines.io import open_log
    from scanlines.io.carmen import CarmenReader
    from scanlines.io.npz import NpzReader
    from scanlines.io.rosbag import RosbagReader
    from scanlines.io.text import iter_lines

    with open_log(path, options=reader_options) as reader:
        if isinstance(reader, NpzReader):
            return reader.n_scans
        if isinstance(reader, RosbagReader):
            return reader.topics[reader.topic][1]
        lines = (line.lstrip() for _, line in iter_lines(reader.path, 1 << 16))
        if isinstance(reader, CarmenReader):
            name = reader.message + " "
            return sum(line.startswith(name) for line in lines)
        return sum(1 for line in lines if line and not line.startswith("#"))
