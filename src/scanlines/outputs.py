"""Putting output files in place safely: all at once or not at all, never by surprise.

Every output scanlines writes goes through here:

* :func:`check_output` before any work: the folder must exist (a typo does not make
  folders), an existing output is not replaced unless ``overwrite`` is given, and
  temporary files left by writers that no longer run are removed;
* the data is written to temporary paths beside the target, named
  ``.<output name>.<process id>.<random>.tmp`` (:func:`temp_path`), so a look at the
  folder says whose they are;
* :func:`commit` moves a group of temporary paths (an output and its ``.meta.json``)
  into place under an exclusive lock on the folder: two runs writing the same output
  cannot interleave, and if one move fails the targets are put back as they were.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import re
import secrets
import shutil
from collections.abc import Iterator, Sequence
from pathlib import Path

from scanlines.errors import ScanlinesError, describe

__all__ = [
    "OutputError",
    "check_output",
    "commit",
    "discard",
    "remove_stale_temps",
    "temp_path",
    "write_error",
    "write_text_atomically",
]


class OutputError(ScanlinesError, OSError):
    """An output cannot be written where it was asked for (missing folder, an existing
    output without ``overwrite``...)."""


def write_error(target: str | Path, error: OSError, what: str = "the output") -> OutputError:
    """An OS error met while writing ``target`` (a full disk, a read-only folder, a file
    size limit) as one line naming ``target``, not the temporary file the error names."""
    if error.errno is not None and error.strerror:
        reason = f"{type(error).__name__}: [Errno {error.errno}] {error.strerror}"
    else:
        reason = describe(error)
    return OutputError(f"{target}: cannot write {what} ({reason})")


def check_output(target: str | Path, *, overwrite: bool, companions: Sequence[Path] = ()) -> Path:
    """Check that ``target`` (and its ``companions``, e.g. the ``.meta.json``) may be
    written, before any work is done; remove stale temporary files of it.

    Raises
    ------
    OutputError
        When the folder does not exist, or ``target`` or a companion exists and
        ``overwrite`` is false, or a companion is a directory.
    """
    target = Path(target)
    folder = target.parent
    if not folder.is_dir():
        raise OutputError(f"{target}: the folder {folder} does not exist (create it first)")
    for path in (target, *companions):
        if path is not target and path.is_dir():
            raise OutputError(f"{path} is a directory; it is in the way of the output {target}")
        if not overwrite and (path.exists() or path.is_symlink()):
            raise OutputError(f"{path} exists; not replacing it (--overwrite replaces it)")
    for path in (target, *companions):
        remove_stale_temps(path)
    return target


def temp_path(target: Path) -> Path:
    """A fresh temporary path beside ``target``, carrying its name and this process's id."""
    return target.with_name(f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")


def _temp_pattern(target: Path) -> re.Pattern[str]:
    return re.compile(rf"\.{re.escape(target.name)}\.(\d+)\.[0-9a-f]+\.tmp")


def remove_stale_temps(target: Path) -> list[Path]:
    """Remove the temporary files and folders of ``target`` whose writing process no
    longer exists (left by a crash or ``kill -9``); return them."""
    pattern = _temp_pattern(target)
    removed = []
    with contextlib.suppress(OSError):
        for entry in target.parent.iterdir():
            match = pattern.fullmatch(entry.name)
            if match and not _process_exists(int(match.group(1))):
                discard(entry)
                removed.append(entry)
    return removed


def _process_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    except OverflowError:
        return False
    return True


def discard(path: Path) -> None:
    """Delete a temporary file or folder, if it is there (on a read-only file system,
    deleting a missing file is an error: it is not tried)."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    elif os.path.lexists(path):
        path.unlink(missing_ok=True)


@contextlib.contextmanager
def folder_lock(folder: Path) -> Iterator[None]:
    """An exclusive lock on ``folder`` among scanlines processes (``flock`` on the folder
    itself: nothing is left behind)."""
    descriptor = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX)
        yield
    finally:
        os.close(descriptor)


def commit(moves: Sequence[tuple[Path, Path]], *, overwrite: bool) -> None:
    """Move each ``(temporary, target)`` into place, all of them or none.

    Under the folder's lock: the targets are checked again (another run may have written
    one since :func:`check_output`), existing targets are set aside, the temporaries moved
    in, and the set-aside ones deleted; a failure puts everything back as it was.
    """
    folder = moves[0][1].parent
    with folder_lock(folder):
        if not overwrite:
            for _, target in moves:
                if target.exists() or target.is_symlink():
                    raise OutputError(f"{target} appeared while writing; not replacing it")
        set_aside: list[tuple[Path, Path]] = []
        placed: list[Path] = []
        try:
            for _, target in moves:
                if target.exists() or target.is_symlink():
                    aside = temp_path(target)
                    os.replace(target, aside)
                    set_aside.append((aside, target))
            for temporary, target in moves:
                os.replace(temporary, target)
                placed.append(target)
        except BaseException:
            for target in placed:
                discard(target)
            for aside, target in set_aside:
                os.replace(aside, target)
            raise
    for aside, _ in set_aside:
        discard(aside)


def write_text_atomically(
    target: str | Path, text: str, *, overwrite: bool = True, make_folder: bool = False
) -> Path:
    """Write ``text`` to ``target`` so that it appears complete or not at all
    (``make_folder``: create its folder, for reports written into a folder of their own)."""
    if make_folder:
        Path(target).parent.mkdir(parents=True, exist_ok=True)
    target = check_output(target, overwrite=overwrite)
    temporary = temp_path(target)
    try:
        with open(temporary, "x", encoding="utf-8", newline="") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(temporary, 0o666 & ~umask())
        commit([(temporary, target)], overwrite=overwrite)
    except OutputError:
        discard(temporary)
        raise
    except OSError as error:  # a full disk, a read-only folder
        discard(temporary)
        raise write_error(target, error) from None
    except BaseException:
        discard(temporary)
        raise
    return target


def umask() -> int:
    """This process's file-creation mask (temporary files are private; outputs are not)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask
