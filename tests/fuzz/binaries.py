"""The compiled code a campaign runs on must not change under it.

A shared object that a process has loaded (``scanlines._core``, numpy's, Cyclone's) is
mapped from its file. Copying another build over that file (``cp``, ``shutil.copyfile``:
the same inode, truncated and written again) changes the mapped pages of every process that
loaded it, and each dies with SIGSEGV at its next call into it: the workers (a ``crash``
defect on whatever input they held), the ROS 2 node, and this runner itself (exit 139) at
its next call into the core, e.g. while it writes the next target's seeds. Installers do
not do this (pip unlinks the old file, ``cmake --install`` writes a new one), but a
developer comparing two builds of the core by copying one over the other does.

:class:`BinaryWatch` notes the identity (device, inode, size, modification time) of every
shared object this process has mapped when the campaign starts (Linux ``/proc/self/maps``),
and of ``scanlines._core``'s file wherever it is. :meth:`BinaryWatch.check` raises
:class:`BinaryChanged` when one was rewritten in place, or when ``scanlines._core`` was
replaced by another file (pip's reinstall: the runner keeps the old build, new workers
would load the new one). The runner checks when a worker or the node died or timed out, when
a worker starts and after each target, so a crash caused by a rewritten binary ends the
campaign with one line naming the file instead of passing for a defect of the input.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import NamedTuple


class BinaryChanged(RuntimeError):
    """A shared object the campaign runs on changed during the campaign."""


class Identity(NamedTuple):
    device: int
    inode: int
    size: int
    mtime_ns: int


def identity(path: Path) -> Identity | None:
    """The file's identity, or ``None`` if there is no file at ``path``."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return Identity(st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def mapped_shared_objects(maps: Path = Path("/proc/self/maps")) -> list[Path]:
    """The shared objects this process has mapped (none where there is no ``/proc``)."""
    try:
        text = maps.read_text()
    except OSError:
        return []
    paths = set()
    for row in text.splitlines():
        fields = row.split(maxsplit=5)
        if len(fields) == 6 and fields[5].startswith("/"):
            name = Path(fields[5]).name
            if name.endswith(".so") or ".so." in name:
                paths.add(Path(fields[5]))
    return sorted(paths)


def core_file() -> Path:
    """The file ``scanlines._core`` was loaded from."""
    from scanlines import _core

    return Path(_core.__file__).resolve()


class BinaryWatch:
    """The identities of ``paths`` and ``core`` when made (default: this process's shared
    objects and ``scanlines._core``'s file). Any of them rewritten in place is a change;
    replaced by another file, only the core (pip replaces files, and a process keeps the
    old one it loaded: only the code under test matters)."""

    def __init__(self, paths: list[Path] | None = None, core: Path | None = None) -> None:
        if paths is None:
            paths, core = mapped_shared_objects(), core or core_file()
        self.core = core
        paths = [*paths, *([core] if core is not None else [])]
        self.identities = {path: identity(path) for path in dict.fromkeys(paths)}

    def changes(self) -> list[str]:
        """What changed since: one description per file."""
        found = []
        for path, before in self.identities.items():
            if before is None:
                continue
            now = identity(path)
            if now is None:
                if path == self.core:
                    found.append(f"{path} was removed")
            elif (now.device, now.inode) == (before.device, before.inode):
                if now != before:
                    when = clock(now.mtime_ns)
                    sizes = f"{before.size} -> {now.size} bytes, the same inode"
                    found.append(f"{path} was rewritten in place at {when} ({sizes})")
            elif path == self.core:
                found.append(f"{path} was replaced by another file at {clock(now.mtime_ns)}")
        return found

    def check(self, when: str = "") -> None:
        """Raise :class:`BinaryChanged` (one line) if a watched file changed."""
        found = self.changes()
        if found:
            context = f" ({when})" if when else ""
            raise BinaryChanged(
                f"{'; '.join(found)} during the campaign{context}: processes that had the old "
                "file loaded crash at their next call into it, so the outcomes since are not "
                "the inputs'; rerun on a build nothing rewrites (e.g. a virtual environment "
                "of its own)"
            )


def clock(ns: int) -> str:
    """A modification time as ``HH:MM:SS`` local time."""
    return time.strftime("%H:%M:%S", time.localtime(ns / 1e9))
