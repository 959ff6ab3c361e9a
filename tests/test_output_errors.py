"""Outputs that cannot be written (a full disk, a read-only folder): one line naming the
output, exit code 2, nothing left behind, for every writer and every figure.

The full disk is real: a 64 KiB tmpfs mounted for the test (ENOSPC as on a full disk),
and the read-only folder a tmpfs mounted read-only (EROFS; ``chmod`` does not stop
root). Where mounting is not permitted (not root, a container without the capability)
these tests are skipped, saying so.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from scanlines.data import sample
from scanlines.io import open_log, open_writer
from scanlines.outputs import OutputError
from test_cli_logs import run

INTEL = sample("intel")


def mounted(folder: Path, options: str) -> Iterator[Path]:
    folder.mkdir()
    try:
        done = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)],
            capture_output=True, text=True, timeout=60,
        )  # fmt: skip
    except FileNotFoundError:
        pytest.skip("no mount command: a full disk or read-only folder cannot be made here")
    if done.returncode != 0:
        reason = done.stderr.strip() or f"exit code {done.returncode}"
        pytest.skip(f"mounting a small tmpfs is not permitted here ({reason})")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], capture_output=True, timeout=60)


@pytest.fixture
def full_disk(tmp_path) -> Iterator[Path]:
    """A folder on a 64 KiB file system: a write past it fails with ENOSPC."""
    yield from mounted(tmp_path / "full", "size=64k")


@pytest.fixture
def read_only(tmp_path) -> Iterator[Path]:
    """A folder on a read-only file system: creating a file fails with EROFS."""
    yield from mounted(tmp_path / "ro", "ro,size=64k")


def command(*args: object, timeout: float = 300) -> subprocess.CompletedProcess:
    """``scanlines ARGS`` in a process of its own (a hang fails the test, not the run)."""
    return subprocess.run(
        [sys.executable, "-m", "scanlines", *map(str, args)],
        capture_output=True, text=True, timeout=timeout,
        env={**os.environ, "COLUMNS": "200"},
    )  # fmt: skip


def names_the_output(out, target: Path, what: str = "output") -> None:
    """Exit code 2 and, as the last line of stderr (notes such as the sensor profile's
    may precede it), one error naming ``target``; no traceback."""
    assert out.returncode == 2, out.stderr
    assert "Traceback" not in out.stderr
    errors = [line for line in out.stderr.splitlines() if line.startswith("scanlines:")]
    assert errors == [out.stderr.strip().splitlines()[-1]], out.stderr
    assert errors[0].startswith(f"scanlines: error: {target}: cannot write the {what} ("), errors
    assert ".tmp" not in errors[0]


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# -- Rerun -----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def rerun_sdk():
    return pytest.importorskip("rerun")


def test_an_rrd_on_a_full_disk_is_one_line_naming_it(rerun_sdk, full_disk) -> None:
    """The SDK's own file sink logged the error and its flush waited for ever."""
    target = full_disk / "x.rrd"
    out = command("run", INTEL, "--out", target, timeout=240)
    names_the_output(out, target)
    assert "No space left on device" in out.stderr
    assert leftovers(full_disk) == []


def test_the_rrd_writer_raises_an_output_error_on_a_full_disk(rerun_sdk, full_disk) -> None:
    from scanlines import extract

    scans = list(open_log(INTEL))[:3]
    extractions = [extract(scan) for scan in scans]
    target = full_disk / "x.rrd"

    def write_until_full() -> None:
        with open_writer(target) as writer:
            for index in range(2000):
                writer.write(index, scans[index % 3], extractions[index % 3])

    with pytest.raises(OutputError, match=rf"^{target}: cannot write the output \(") as error:
        write_until_full()
    assert "\n" not in str(error.value)
    assert leftovers(full_disk) == []


def test_an_rrd_in_a_read_only_folder_is_one_line_naming_it(rerun_sdk, read_only) -> None:
    target = read_only / "x.rrd"
    names_the_output(command("run", INTEL, "--scans", "0:3", "--out", target), target)


# -- other writers ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["x.jsonl", "x.mcap", "xbag"])
def test_a_read_only_folder_names_the_output(read_only, name) -> None:
    target = read_only / name
    names_the_output(run("run", INTEL, "--scans", "0:3", "--out", target), target)


def test_calibrate_names_a_profile_it_cannot_write(read_only) -> None:
    target = read_only / "p.json"
    names_the_output(run("calibrate", INTEL, "--out", target), target)


# -- figures ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def one_scan(tmp_path_factory) -> Path:
    scan = next(iter(open_log(INTEL)))
    path = tmp_path_factory.mktemp("scan") / "scan.npz"
    np.savez(path, ranges=scan.ranges, angle_min=scan.angle_min,
             angle_increment=scan.angle_increment, range_max=scan.range_max)  # fmt: skip
    return path


def figure_commands(folder: Path, one_scan: Path) -> dict[str, tuple[list[object], Path]]:
    """Each command that draws, writing a figure into ``folder``: its arguments, the
    figure."""
    return {
        "plot --scan": (["plot", INTEL, "--scan", "3", "-o", folder / "a.png"], folder / "a.png"),
        "plot --scans": (
            ["plot", INTEL, "--scans", "0:40", "-o", folder / "b.png"],
            folder / "b.png",
        ),
        "extract --plot": (["extract", one_scan, "--plot", folder / "c.svg"], folder / "c.svg"),
        "calibrate --plot": (
            ["calibrate", INTEL, "--out", folder.parent / "p.json", "--plot", folder / "d.png"],
            folder / "d.png",
        ),
    }


FIGURE_COMMANDS = ["plot --scan", "plot --scans", "extract --plot", "calibrate --plot"]


@pytest.mark.parametrize("which", FIGURE_COMMANDS)
def test_a_figure_in_a_read_only_folder_is_one_line_naming_it(read_only, one_scan, which):
    args, target = figure_commands(read_only, one_scan)[which]
    names_the_output(run(*args), target, "figure")
    assert leftovers(read_only) == []


@pytest.mark.parametrize("which", FIGURE_COMMANDS)
def test_a_figure_on_a_full_disk_is_one_line_naming_it(full_disk, one_scan, which):
    (full_disk / "filler").write_bytes(b"\0" * 60_000)  # less than a figure is left
    args, target = figure_commands(full_disk, one_scan)[which]
    out = run(*args)
    names_the_output(out, target, "figure")
    assert "No space left on device" in out.stderr
    assert leftovers(full_disk) == ["filler"]


def test_extract_does_not_replace_a_figure_without_overwrite(one_scan, tmp_path) -> None:
    figure = tmp_path / "scan.png"
    figure.write_bytes(b"mine")
    out = run("extract", one_scan, "--plot", figure)
    assert out.returncode == 2, out.stderr
    assert out.stderr.strip().splitlines() == [
        f"scanlines: error: {figure} exists; not replacing it (--overwrite replaces it)"
    ]
    assert figure.read_bytes() == b"mine"
    out = run("extract", one_scan, "--plot", figure, "--overwrite")
    assert out.returncode == 0, out.stderr
    assert figure.read_bytes()[:4] == b"\x89PNG"


def test_extract_checks_the_figure_folder_before_reading(tmp_path) -> None:
    target = tmp_path / "missing" / "scan.png"
    scan = tmp_path / "scan.npz"
    np.savez(scan, ranges=np.full(90, 2.0), angle_min=0.0, angle_increment=0.01)
    out = run("extract", scan, "--plot", target)
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        f"scanlines: error: {target}: the folder {target.parent} does not exist (create it first)"
    ]
