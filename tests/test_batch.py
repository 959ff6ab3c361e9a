"""Extractor.batch and the chunked log runner give exactly the single-call results."""

from __future__ import annotations

import numpy as np
import pytest

import scanlines
from scanlines import Extraction, Extractor, Scan, ScanError
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.runs.runner import run_log
from scanlines.sim import random_scene


def same(a: Extraction, b: Extraction) -> bool:
    return (
        np.array_equal(a.first, b.first)
        and np.array_equal(a.last, b.last)
        and np.array_equal(a.breakpoints, b.breakpoints)
        and np.array_equal(a.corners, b.corners)
        and np.array_equal(a.outliers, b.outliers)
        and np.allclose(a.lines, b.lines, rtol=0, atol=1e-9, equal_nan=True)
        and dict(a.params) == dict(b.params)
    )


@pytest.fixture(scope="module")
def real_stacks():
    stacks = {}
    for name in ("intel", "freiburg"):
        scans = list(open_log(sample(name)))[:40]
        stacks[name] = scans
    return stacks


@pytest.mark.parametrize("method", scanlines.method_names())
def test_batch_equals_single_calls_on_real_excerpts(real_stacks, method):
    # Two extractors: one that learns the noise learns it from the scans it has seen.
    batched, single = Extractor(method), Extractor(method)
    for scans in real_stacks.values():
        first = scans[0]
        stack = np.stack([s.ranges for s in scans])
        batch = batched.batch(
            stack, first.angle_min, first.angle_increment, first.range_min, first.range_max
        )
        assert all(same(b, single(s)) for b, s in zip(batch, scans, strict=True))


@pytest.mark.parametrize("sensor", ["lms_05deg", "tim571", "urg04lx"])
def test_batch_equals_single_calls_on_simulated_scans(sensor):
    scans = [random_scene(seed, sensor).scan(seed).scan for seed in range(8)]
    first = scans[0]
    stack = np.stack([s.ranges for s in scans])
    for preset in (None, "paper"):
        extractor = Extractor(preset=preset)
        batch = extractor.batch(
            stack, first.angle_min, first.angle_increment, first.range_min, first.range_max
        )
        assert all(same(b, extractor(s)) for b, s in zip(batch, scans, strict=True))


def test_batch_refuses_what_scan_refuses():
    extractor = Extractor()
    with pytest.raises(ScanError, match="2-D"):
        extractor.batch(np.zeros(10), 0.0, 0.01)
    with pytest.raises(ScanError, match="angle_increment"):
        extractor.batch(np.zeros((2, 10)), 0.0, 0.0)
    with pytest.raises(ScanError, match="real numbers"):
        extractor.batch(np.array([["a", "b"]]), 0.0, 0.01)


class ListReader:
    """A reader over given scans (two geometries), as run_log sees a log."""

    path = "memory"
    error_count = 0

    def __init__(self, scans):
        self.scans = scans

    def enumerate(self):
        yield from enumerate(self.scans)


class Recorder:
    def __init__(self):
        self.rows = []

    def write(self, index, scan, extraction):
        self.rows.append((index, extraction))


def test_run_log_chunks_by_geometry_and_matches_single_calls(real_stacks):
    scans = real_stacks["intel"][:7] + real_stacks["freiburg"][:5] + real_stacks["intel"][7:12]
    extractor = Extractor()
    recorder = Recorder()
    summary = run_log(ListReader(scans), extractor, writer=recorder, chunk=4)
    assert [i for i, _ in recorder.rows] == list(range(len(scans)))
    assert all(same(e, extractor(s)) for (_, e), s in zip(recorder.rows, scans, strict=True))
    assert summary.scans == len(scans)
    assert summary.segments == sum(len(e) for _, e in recorder.rows)


def test_scan_and_batch_share_one_validity_rule():
    ranges = np.array([[1.0, 0.0, -1.0, np.inf, np.nan, 0.05, 35.0, 2.0]])
    batch = Extractor().batch(ranges, 0.0, 0.1, range_min=0.1, range_max=30.0)
    scan = Scan(ranges[0], 0.0, 0.1, range_min=0.1, range_max=30.0)
    assert same(batch[0], Extractor()(scan))


def sawtooth_scans(rows: int = 3) -> list[Scan]:
    """Scans of 30 ramps of 12 beams, each starting 1 m nearer than the last one ends:
    more segments and breakpoints per scan than a stack table first holds."""
    beams = np.arange(360)
    rng = np.random.default_rng(7)
    ramp = 2.0 + 0.08 * (beams % 12)
    return [
        Scan(ramp + rng.normal(0.0, 0.003, beams.size), -np.pi, np.radians(1.0), range_max=30.0)
        for _ in range(rows)
    ]


@pytest.mark.parametrize("method", ["adaptive", "iepf", "split_merge", "partition"])
def test_stack_kernel_rows_are_the_single_scan_results(method):
    """Many segments and events per scan: every row of one stack call is what the scan
    gives alone."""
    scans = sawtooth_scans()
    extractor = Extractor(method)
    first = scans[0]
    table = extractor.batch(
        np.stack([s.ranges for s in scans]), first.angle_min, first.angle_increment, 0.0, 30.0
    )
    assert max(table.counts("segments")) > 5
    for row, scan in enumerate(scans):
        assert same(table[row], extractor(scan))
