"""Readers and writers stream: peak memory does not grow with the log."""

from __future__ import annotations

import json
import tracemalloc
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from io_helpers import make_extraction

from scanlines.io import open_log, open_writer
from scanlines.scan import Scan

N_SCANS = 100_000
N_BEAMS = 8
MEMORY_BOUND = 2_000_000  # bytes: a few hundred scans' worth, far below the files


def write_big_carmen_log(path: Path, n_scans: int) -> None:
    """A CARMEN log of ``n_scans`` short FLASER records (1000 distinct range rows, cycled)."""
    rows = np.round(np.random.default_rng(0).uniform(0.5, 9.5, (1000, N_BEAMS)), 2)
    texts = [" ".join(f"{v:.2f}" for v in row) for row in rows]
    with path.open("w") as fh:
        fh.write("# generated for the streaming test\n")
        for i in range(n_scans):
            t = f"{i * 0.1:.3f}"
            x = f"{i * 0.01:.2f}"
            fh.write(f"FLASER {N_BEAMS} {texts[i % 1000]} {x} 0 0.1 {x} 0 0.1 {t} host {t}\n")


def traced_peak(work: Callable[[], object]) -> tuple[object, int]:
    tracemalloc.start()
    try:
        result = work()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return result, peak


@pytest.mark.slow
def test_reading_a_large_log_keeps_memory_bounded(tmp_path) -> None:
    path = tmp_path / "big.log"
    write_big_carmen_log(path, N_SCANS)
    size = path.stat().st_size
    assert size > 9_000_000

    def read_all() -> tuple[int, float]:
        count, last = 0, 0.0
        for scan in open_log(path):
            count += 1
            last = scan.timestamp
        return count, last

    (count, last), peak = traced_peak(read_all)
    assert count == N_SCANS
    assert last == pytest.approx((N_SCANS - 1) * 0.1)
    assert peak < MEMORY_BOUND
    assert peak < size / 5


@pytest.mark.slow
def test_writing_many_scans_keeps_memory_bounded(tmp_path) -> None:
    n_scans = 10_000
    scan = Scan(np.linspace(1.0, 2.0, 50), -1.0, 0.04, timestamp=1.0, pose=(1.0, 2.0, 0.5))
    extraction = make_extraction(3)
    jsonl, table = tmp_path / "out.jsonl", tmp_path / "out.csv"

    def write_all() -> None:
        with open_writer(jsonl) as a, open_writer(table) as b:
            for index in range(n_scans):
                a.write(index, scan, extraction)
                b.write(index, scan, extraction)

    _, peak = traced_peak(write_all)
    assert jsonl.stat().st_size > 2_500_000
    assert peak < MEMORY_BOUND
    with jsonl.open() as fh:
        assert sum(1 for _ in fh) == n_scans
    assert json.loads(Path(f"{table}.meta.json").read_text())["counts"]["segments"] == 3 * n_scans
