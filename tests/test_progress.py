"""Progress of the long commands: drawn on stderr when it is a terminal (a real
pseudo-terminal here), nothing at all when stderr is piped."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
from pathlib import Path

import pytest

from scanlines.data import sample
from scanlines.io import open_log
from scanlines.map.poses import write_tum

INTEL = str(sample("intel"))
#: Variables that would make rich take a pipe for a terminal, or a terminal for none.
TERMINAL_OVERRIDES = ("FORCE_COLOR", "TTY_COMPATIBLE", "TTY_INTERACTIVE", "NO_COLOR")


def _environment() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in TERMINAL_OVERRIDES}
    return {**env, "TERM": "xterm-256color", "COLUMNS": "120"}


def on_terminal(args: list[str], cwd: Path) -> tuple[int, str]:
    """``scanlines ARGS`` with stderr on a pseudo-terminal: exit code, what the terminal got."""
    leader, follower = pty.openpty()
    command = [sys.executable, "-m", "scanlines", *args]
    process = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=follower, cwd=cwd, env=_environment()
    )
    os.close(follower)
    chunks = []
    while True:
        try:
            data = os.read(leader, 65536)
        except OSError:  # the command has ended: the terminal is closed
            break
        if not data:
            break
        chunks.append(data)
    os.close(leader)
    return process.wait(timeout=300), b"".join(chunks).decode(errors="replace")


def piped(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    command = [sys.executable, "-m", "scanlines", *args]
    return subprocess.run(
        command, capture_output=True, text=True, cwd=cwd, env=_environment(), timeout=300
    )


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    """A line map of the Intel excerpt, its first pose, and 30 of its poses as TUM."""
    folder = tmp_path_factory.mktemp("progress")
    done = piped(["map", INTEL, "--out", "map.json", "--scans", "60"], folder)
    assert done.returncode == 0, done.stderr
    with open_log(INTEL) as reader:
        scans = [scan for _, scan in zip(range(30), reader, strict=False)]
    write_tum(folder / "est.tum", [(s.timestamp, s.pose) for s in scans])
    t, (x, y, yaw) = scans[0].timestamp, scans[0].pose
    (folder / "initial").write_text(f"{t},{x},{y},{yaw}")
    return folder


#: Each long command, and the words its progress shows.
COMMANDS = {
    "map": (
        ["map", INTEL, "--out", "m.geojson", "--scans", "40", "--overwrite"],
        "mapping intel_excerpt",
    ),
    "map --align": (
        ["map", INTEL, "--align", "--out", "a.geojson", "--scans", "40", "--overwrite"],
        "tracking and mapping intel_excerpt",
    ),
    "localize": (
        [
            "localize",
            INTEL,
            "--map",
            "map.json",
            "--initial-pose",
            "{initial}",
            "--out",
            "l.tum",
            "--overwrite",
        ],
        "localising intel_excerpt",
    ),
    "eval sim": (
        ["eval", "sim", "-s", "lms_1deg", "-n", "2", "-m", "iepf", "--no-plots", "-j", "1"],
        "evaluating",
    ),
    "eval family": (
        ["eval", "family", "-n", "1", "--family-count", "1", "-m", "iepf", "--no-plots", "-j", "1"],
        "evaluating",
    ),
    "eval labels": (["eval", "labels", "urg", "-m", "iepf"], "scoring hand-labelled frames"),
    "eval real": (
        ["eval", "real", INTEL, "--scans", "20", "--pairs", "3", "-m", "iepf"],
        "pairs, then scans per method",
    ),
    "eval map": (["eval", "map", INTEL, "--scans", "40"], "scoring intel_excerpt"),
    "eval trajectory": (
        ["eval", "trajectory", "est.tum", "--reference", INTEL, "--out", "t.json"],
        "reading est.tum",
    ),
    "bench": (
        [
            "bench",
            "--quick",
            "-m",
            "iepf",
            "-s",
            "lms_1deg",
            "--no-scaling",
            "--no-batch",
            "--no-pipeline",
            "--real-scans",
            "5",
        ],
        "sim:lms_1deg",
    ),
}


def _args(name: str, folder: Path) -> list[str]:
    initial = (folder / "initial").read_text()
    return [a.replace("{initial}", initial) for a in COMMANDS[name][0]]


@pytest.mark.parametrize(
    "name", [pytest.param(n, marks=pytest.mark.slow) if n == "bench" else n for n in COMMANDS]
)
def test_progress_on_a_terminal_and_nothing_when_piped(name, inputs):
    args, words = _args(name, inputs), COMMANDS[name][1]
    code, terminal = on_terminal(args, inputs)
    assert code == 0, terminal
    assert "\x1b[" in terminal, terminal  # drawn, then cleared (transient)
    assert words in terminal, terminal
    assert "0:00:" in terminal, terminal  # the time taken
    done = piped(args, inputs)
    assert done.returncode == 0, done.stderr
    assert "\x1b" not in done.stderr
    assert "0:00:" not in done.stderr
    assert words not in done.stderr
