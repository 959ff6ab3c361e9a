"""Ctrl-C and SIGTERM stop ``scanlines run`` cleanly at any moment: exit 130 or 143, a
one-line note and no traceback on stderr, no output and no temporary file left.

Each run is a real process stopped at a random moment (start-up, kernel loading, the
profile, extraction, writing). CI stops a few runs of each kind; ``pytest --long``
stops 30 of each.
"""

from __future__ import annotations

import gzip
import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from scanlines.data import sample

pytestmark = pytest.mark.slow  # processes stopped at random moments

RUNS = 5
LONG_RUNS = 30


@pytest.fixture(scope="module")
def long_log(tmp_path_factory) -> Path:
    """The Intel excerpt 20 times over (6,000 scans): a run of a few seconds."""
    text = gzip.decompress(sample("intel").read_bytes())
    path = tmp_path_factory.mktemp("signals") / "intel_x20.clf"
    path.write_bytes(text * 20)
    return path


def stop_run(log: Path, folder: Path, signum: int, after: float) -> tuple[int, str, list[str]]:
    """Start ``scanlines run``, send ``signum`` after ``after`` seconds; return the exit
    code, stderr, and what is left in ``folder``."""
    out = folder / "out.jsonl"
    process = subprocess.Popen(
        [sys.executable, "-m", "scanlines", "run", str(log), "--out", str(out), "-j", "2"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "COLUMNS": "100"},
    )
    time.sleep(after)
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=60)
    return process.returncode, stderr, sorted(p.name for p in folder.iterdir())


def assert_complete(folder: Path) -> None:
    """The output and its metadata, both whole and of the same run."""
    assert sorted(p.name for p in folder.iterdir()) == ["out.jsonl", "out.jsonl.meta.json"]
    meta = json.loads((folder / "out.jsonl.meta.json").read_text())
    lines = (folder / "out.jsonl").read_text().splitlines()
    assert meta["counts"]["scans"] == len(lines) == 6000


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_stopped_runs_are_clean(long_log, tmp_path, request, signum, code) -> None:
    runs = LONG_RUNS if request.config.getoption("--long") else RUNS
    rng = random.Random(signum)
    outcomes = []
    for k in range(runs):
        folder = tmp_path / f"run{k}"
        folder.mkdir()
        after = rng.uniform(0.3, 4.0)
        returncode, stderr, left = stop_run(long_log, folder, signum, after)
        if returncode == 0:  # finished before the signal: a complete output is right
            assert_complete(folder)
            outcomes.append("finished")
            continue
        assert returncode == code, (after, returncode, stderr)
        assert "Traceback" not in stderr, (after, stderr)
        assert "Error" not in stderr, (after, stderr)
        assert stderr.strip().splitlines()[-1] in (
            "scanlines: interrupted",
            "scanlines: terminated",
        )
        if left:  # stopped after the output was committed, while printing the summary
            assert_complete(folder)
        outcomes.append("stopped")
    print(f"{signal.Signals(signum).name}: {outcomes.count('stopped')} stopped, "
          f"{outcomes.count('finished')} finished first, of {runs}")  # fmt: skip
    assert outcomes.count("stopped") >= runs // 2, outcomes


STOPPED_WHILE_PARSING = """
import sys
from typer.core import TyperGroup
from scanlines.cli import main

def interrupted(*args, **kwargs):
    raise KeyboardInterrupt  # Ctrl-C while the options are parsed

TyperGroup.make_context = interrupted
sys.argv = ["scanlines", "run", sys.argv[1]]
main()
"""


def test_ctrl_c_while_options_are_parsed_still_says_its_line() -> None:
    """typer turns an interrupt during parsing into exit 130 of its own, with no line."""
    done = subprocess.run(
        [sys.executable, "-c", STOPPED_WHILE_PARSING, str(sample("intel"))],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 130, done.stderr
    assert done.stderr.strip().splitlines() == ["scanlines: interrupted"]
