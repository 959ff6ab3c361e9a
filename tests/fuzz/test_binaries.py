"""A shared object rewritten under a campaign ends it with one line, not with crashes
passed off as defects of the inputs (``binaries.py``).

The 5,000-input campaign of issue 38 died with SIGSEGV (exit 139) after its log target:
another build of ``scanlines._core`` had been copied over the installed file in place,
which killed both workers at once (three "crash" defects that replayed cleanly) and then
the runner at its next call into the core.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from scanlines.data import sample

from . import run
from .binaries import BinaryChanged, BinaryWatch, core_file, mapped_shared_objects
from .channels import SUCCESS, Worker


def rewrite_in_place(path: Path, data: bytes) -> None:
    """What ``cp NEW path`` does to an existing file: the same inode, truncated."""
    before = os.stat(path).st_ino
    with open(path, "r+b") as fh:
        fh.truncate(0)
        fh.write(data)
    os.utime(path, ns=(os.stat(path).st_atime_ns, os.stat(path).st_mtime_ns + 1_000_000))
    assert os.stat(path).st_ino == before


def replace(path: Path, data: bytes) -> None:
    """What pip does: a new file under the name."""
    new = path.with_name(path.name + ".new")
    new.write_bytes(data)
    os.replace(new, path)


@pytest.fixture
def files(tmp_path: Path) -> tuple[Path, Path]:
    core, other = tmp_path / "_core.so", tmp_path / "libother.so"
    core.write_bytes(b"tuned build")
    other.write_bytes(b"a library")
    return core, other


def test_nothing_changed_passes(files: tuple[Path, Path]) -> None:
    core, other = files
    watch = BinaryWatch([other], core=core)
    watch.check()
    assert watch.changes() == []


@pytest.mark.parametrize("which", ["core", "other"])
def test_a_file_rewritten_in_place_is_a_change(files: tuple[Path, Path], which: str) -> None:
    core, other = files
    watch = BinaryWatch([other], core=core)
    target = core if which == "core" else other
    rewrite_in_place(target, b"portable build")
    with pytest.raises(BinaryChanged, match="rewritten in place") as raised:
        watch.check("a worker died")
    message = str(raised.value)
    assert str(target) in message
    assert "a worker died" in message
    assert len(message.splitlines()) == 1


def test_the_core_replaced_is_a_change_another_library_is_not(
    files: tuple[Path, Path],
) -> None:
    core, other = files
    watch = BinaryWatch([other], core=core)
    replace(other, b"a newer library")  # the runner keeps the one it loaded
    watch.check()
    replace(core, b"another build")  # new workers would run other code
    with pytest.raises(BinaryChanged, match="replaced by another file"):
        watch.check()


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="Linux /proc")
def test_the_default_watch_covers_the_loaded_core() -> None:
    assert core_file() in mapped_shared_objects()
    watch = BinaryWatch()
    assert core_file() in watch.identities
    assert watch.core == core_file()
    assert any("numpy" in str(path) for path in watch.identities)


@pytest.mark.slow
def test_a_worker_dead_after_a_rewrite_ends_the_campaign(files: tuple[Path, Path]) -> None:
    """A dead worker is restarted and its input run again, unless a watched file changed:
    then the campaign ends (before, the rewrite passed for a crash of the input)."""
    core, other = files
    with Worker(core.parent / "worker", watch=BinaryWatch([other], core=core)) as worker:
        worker.start()
        os.kill(worker.process.pid, signal.SIGSEGV)
        worker.process.join(10)
        outcome = worker.run("library fail", sample("intel"))
        assert outcome.kind == SUCCESS  # nothing changed: a new worker reads it

        rewrite_in_place(core, b"portable build")
        os.kill(worker.process.pid, signal.SIGSEGV)
        worker.process.join(10)
        with pytest.raises(BinaryChanged, match="a worker starting"):
            worker.run("library fail", sample("intel"))


@pytest.mark.slow
def test_the_runner_says_so_in_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """``python -m tests.fuzz.run`` exits 2 with one line naming the file."""
    core = tmp_path / "_core.so"
    core.write_bytes(b"tuned build")
    watch = BinaryWatch([], core=core)
    rewrite_in_place(core, b"portable build")
    monkeypatch.setattr(run, "BinaryWatch", lambda: watch)
    assert run.main(["--count", "2", "--targets", "maps", "--workdir", str(tmp_path / "w")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert str(core) in err[0]
    assert "rewritten in place" in err[0]
