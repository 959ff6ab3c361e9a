"""A ROS 2 bag on disk: a bag directory, the storage files it holds, their size."""

from __future__ import annotations

from pathlib import Path

from scanlines.errors import LogFormatError

_STORAGE_SUFFIXES = (".db3", ".mcap")


def _storage_bytes(path: Path) -> int:
    """Bytes of a bag file, or of the files of a bag directory."""
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def is_ros2_bag_dir(path: Path) -> bool:
    """True for a directory with ``metadata.yaml`` or with ``.db3``/``.mcap`` storage files."""
    if not path.is_dir():
        return False
    return (path / "metadata.yaml").exists() or any(
        child.suffix in _STORAGE_SUFFIXES for child in path.iterdir()
    )


def _bag_paths(path: Path) -> list[Path]:
    """The path(s) to hand to AnyReader (a directory without metadata: its storage file)."""
    if path.is_dir() and not (path / "metadata.yaml").exists():
        storage = sorted(c for c in path.iterdir() if c.suffix in _STORAGE_SUFFIXES)
        if len(storage) != 1:
            raise LogFormatError(
                f"a ROS 2 bag directory without metadata.yaml must hold exactly one .db3/.mcap "
                f"file, found {len(storage)}",
                path=path,
            )
        return storage
    return [path]
