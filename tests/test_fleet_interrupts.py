"""Ctrl-C on ``scanlines run ... --format parquet --scheduler local``: a real Dask
LocalCluster in a process of its own, stopped by SIGINT at the moments that went wrong.

Each run must stop with exactly one line on stderr (``scanlines: interrupted``, exit 130)
and leave no worker process. SIGINT while the workers started was lost when another
thread of the command took it (the run went on to its end, exit 0); when the command's
main thread took it, the cluster was left unclosed and multiprocessing's resource tracker
added two lines about leaked semaphores.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from scanlines.data import sample

pytestmark = pytest.mark.slow  # a Dask LocalCluster per test

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("fleet") / "logs"
    folder.mkdir()
    shutil.copy(sample("intel"), folder)
    shutil.copy(sample("freiburg"), folder)
    return folder


def spawned_children(parent: int) -> list[int]:
    """The processes ``parent`` started through multiprocessing's spawn (Dask's workers)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        if ppid == parent and b"spawn_main" in cmdline:
            found.append(int(entry.name))
    return found


def running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def to_main_thread(pid: int, signum: int) -> None:
    """``signum`` to ``pid``'s main thread itself (``tgkill``), not to any of its threads."""
    number = {"x86_64": 234, "aarch64": 131}.get(os.uname().machine)
    if number is None:
        pytest.skip(f"tgkill's system call number on {os.uname().machine} is not known here")
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.syscall(number, pid, pid, signum) != 0:
        raise OSError(ctypes.get_errno(), "tgkill failed")


SEND = {
    "the command": lambda pid: os.kill(pid, signal.SIGINT),  # kill -INT PID
    "its process group": lambda pid: os.killpg(pid, signal.SIGINT),  # Ctrl-C in a terminal
    "its main thread": lambda pid: to_main_thread(pid, signal.SIGINT),
}
CASES = [
    ("while the workers start", "the command"),
    ("while the workers start", "its process group"),
    ("while the workers start", "its main thread"),
    ("after the first part", "its process group"),
]


@pytest.mark.parametrize(("when", "to"), CASES)
def test_ctrl_c_on_a_dask_run_prints_one_line(logs, tmp_path, when, to) -> None:
    """The workers ignore Ctrl-C; the command stops the cluster and says so in one line."""
    dataset = tmp_path / "features"
    process = subprocess.Popen(
        [sys.executable, "-m", "scanlines", "run", logs, "--out", dataset, "--format",
         "parquet", "--scheduler", "local", "-j", "2", "--chunk-records", "20"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True,
    )  # fmt: skip
    deadline = time.monotonic() + 240
    workers: list[int] = []
    while (
        not workers
        if when == "while the workers start"
        else not list(dataset.glob("_staging/segments/*/*.parquet"))
    ):
        assert time.monotonic() < deadline, "the run did not get there"
        assert process.poll() is None, process.communicate()[1]
        workers = spawned_children(process.pid)
        time.sleep(0.01)
    workers = workers or spawned_children(process.pid)
    SEND[to](process.pid)
    _, stderr = process.communicate(timeout=240)
    assert process.returncode == 130, stderr
    assert stderr.strip().splitlines() == ["scanlines: interrupted"], stderr
    assert not [p for p in dataset.glob("_logs/*.json") if ".pending" not in p.name]
    deadline = time.monotonic() + 60
    while any(running(pid) for pid in workers):
        assert time.monotonic() < deadline, f"workers left running: {workers}"
        time.sleep(0.1)
