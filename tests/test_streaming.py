"""The streaming path of ``scanlines run``: the flat batch table, chunk encoders, and jobs
that change nothing in the output."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import scanlines
from scanlines import Extractor, ParameterError
from scanlines.data import sample
from scanlines.extraction import ExtractionTable
from scanlines.io import open_log
from scanlines.io.writers import CSV_COLUMNS
from scanlines.runs.runner import default_jobs, run_log, run_log_to_file

COLUMNS = ("first", "last", "n_points", "lines", "covariances", "end_kinds")
EVENTS = ("breakpoints", "corners", "outliers")


@pytest.fixture(scope="module")
def intel():
    with open_log(sample("intel")) as reader:
        return list(reader)


@pytest.fixture(scope="module")
def table(intel):
    first = intel[0]
    stack = np.stack([scan.ranges for scan in intel[:60]])
    return Extractor().batch(
        stack, first.angle_min, first.angle_increment, first.range_min, first.range_max
    )


def test_table_rows_are_the_single_call_extractions(intel, table):
    extractor = Extractor()
    assert len(table) == 60
    for scan, row in zip(intel[:60], table, strict=True):
        single = extractor(scan)
        for name in (*COLUMNS, *EVENTS):
            np.testing.assert_array_equal(getattr(row, name), getattr(single, name))
        assert row.to_dict() == single.to_dict()


def test_table_columns_are_the_rows_concatenated(table):
    counts = table.counts()
    assert counts.sum() == len(table.first)
    np.testing.assert_array_equal(table.segment_scan, np.repeat(np.arange(60), counts))
    for name in EVENTS:
        joined = np.concatenate([getattr(row, name) for row in table])
        np.testing.assert_array_equal(getattr(table, name), joined)
        assert table.counts(name).sum() == len(joined)
    assert not table.lines.flags.writeable
    assert not table[3].lines.flags.writeable


def test_table_pickles_and_indexes_like_a_sequence(table):
    copy = pickle.loads(pickle.dumps(table))
    assert len(copy) == len(table)
    for name in (*COLUMNS, *EVENTS):
        np.testing.assert_array_equal(getattr(copy, name), getattr(table, name))
    assert copy[-1].to_dict() == table[59].to_dict()
    with pytest.raises(IndexError, match="scan 60 out of range"):
        table[60]
    with pytest.raises(AttributeError):
        table.no_such_column  # noqa: B018


@settings(max_examples=25, deadline=None)
@given(counts=st.lists(st.integers(0, 4), min_size=0, max_size=6))
def test_table_of_extractions_round_trips(table, counts):
    rows = [table[k % len(table)] for k in counts]
    joined = ExtractionTable.concatenate(rows, "adaptive", table.params)
    assert len(joined) == len(rows)
    for row, back in zip(rows, joined, strict=True):
        for name in (*COLUMNS, *EVENTS):
            np.testing.assert_array_equal(getattr(back, name), getattr(row, name))


@pytest.mark.parametrize("suffix", [".jsonl", ".csv", ".mcap"])
def test_jobs_write_the_same_bytes_as_one_job(tmp_path, suffix):
    """300 scans in chunks of 8: 38 chunks over 3 threads, out of order inside."""
    extractor = Extractor()
    outputs = []
    for jobs in (1, 3):
        out = tmp_path / f"jobs{jobs}{suffix}"
        with open_log(sample("intel")) as reader:
            summary = run_log_to_file(reader, extractor, out, jobs=jobs)
        assert summary.scans == 300
        assert summary.jobs == jobs
        outputs.append(out.read_bytes())
    if suffix == ".mcap":  # a bag records its own write time: compare its messages
        outputs = [_bag_messages(tmp_path / f"jobs{j}{suffix}") for j in (1, 3)]
    assert outputs[0] == outputs[1]


def test_many_small_chunks_on_many_threads_keep_the_log_order(intel):
    class Reader:
        error_count = 0

        def enumerate(self):
            return enumerate(intel)

    seen = []
    summary = run_log(Reader(), Extractor(), chunk=5, jobs=4, on_scan=seen.append)
    assert seen == list(range(300))
    assert summary.scans == 300


def test_cli_jobs_output_is_byte_identical(tmp_path):
    texts = []
    for jobs in ("1", "2"):
        out = tmp_path / f"j{jobs}.jsonl"
        done = scanlines("run", sample("intel"), "--out", out, "--jobs", jobs)
        assert done.returncode == 0, done.stderr
        assert f"({jobs} jobs)" in done.stdout
        texts.append(out.read_bytes())
    assert texts[0] == texts[1]
    first = json.loads(texts[0].splitlines()[0])
    assert set(first) == {
        "scan", "timestamp", "pose", "segments", "breakpoints", "corners",
        "breakpoint_xy", "corner_xy",
    }  # fmt: skip


def test_csv_chunk_has_one_row_per_segment_and_empty_cells_for_nan(tmp_path, intel):
    from scanlines.io.writers import encode_csv_rows

    extractor = Extractor()
    rows = extractor(intel[0])
    table = ExtractionTable.concatenate([rows], "adaptive", rows.params)
    lines = encode_csv_rows([7], [intel[0]], table).decode().splitlines()
    events = len(rows.breakpoints) + len(rows.corners)  # a row each, after the segments
    assert len(lines) == len(rows) + events
    feature = CSV_COLUMNS.index("feature")
    assert all(line.split(",")[feature] == "segment" for line in lines[: len(rows)])
    cells = lines[0].split(",")
    assert len(cells) == len(CSV_COLUMNS)
    assert cells[0] == "7"
    assert int(cells[2]) == rows.first[0]
    nan_lines = np.array(rows.lines)
    nan_lines[0, 6] = np.nan  # rms
    broken = ExtractionTable(
        {**table.columns, "lines": nan_lines}, table.offsets, "adaptive", rows.params
    )
    cells = encode_csv_rows([7], [intel[0]], broken).decode().splitlines()[0].split(",")
    assert cells[CSV_COLUMNS.index("rms")] == ""


def test_default_jobs_is_every_core_this_process_may_use():
    import os

    assert default_jobs() == len(os.sched_getaffinity(0))


def _bag_messages(path):
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return [(c.topic, t, raw) for c, t, raw in reader.messages()]


@pytest.mark.parametrize("jobs", [2, 3, 100])
def test_batch_on_threads_gives_the_same_table(intel, table, jobs):
    first = intel[0]
    stack = np.stack([scan.ranges for scan in intel[:60]])
    threaded = Extractor().batch(
        stack, first.angle_min, first.angle_increment, first.range_min, first.range_max,
        jobs=jobs,
    )  # fmt: skip
    for name in (*COLUMNS, *EVENTS):
        np.testing.assert_array_equal(getattr(threaded, name), getattr(table, name))
    for key, offsets in table.offsets.items():
        np.testing.assert_array_equal(threaded.offsets[key], offsets)


def test_batch_refuses_a_bad_jobs_count(intel):
    with pytest.raises(ParameterError, match="jobs must be an integer >= 1"):
        Extractor().batch(np.ones((2, 10)), 0.0, 0.01, jobs=0)


def test_a_process_pool_maps_an_extractor_over_scans(intel):
    """Extractor and Extraction pickle: `pool.map(extractor, scans)` works and equals the
    calls in this process."""
    from concurrent.futures import ProcessPoolExecutor

    extractor = Extractor()
    with ProcessPoolExecutor(2) as pool:
        remote = list(pool.map(extractor, intel[:6]))
    for scan, result in zip(intel[:6], remote, strict=True):
        here = extractor(scan)
        assert pickle.loads(pickle.dumps(here)).to_dict() == here.to_dict()
        assert result.to_dict() == here.to_dict()


@pytest.mark.parametrize(
    ("in_file", "text", "expected"),
    [
        (None, None, None),
        (0, None, None),  # a declared 0 (a damaged index) is not a count
        (100, None, 100),
        (100, "10:20", 10),
        (100, "90:200", 10),
        (100, "::3", 34),
        (None, "5:25:2", 10),
        (None, "7", 7),  # N: the first N scans, in every command
        (None, "7:8", 1),
        (100, "150:", 0),
    ],
)
def test_selected_count_bounds_the_progress_bar(in_file, text, expected):
    from scanlines.runs.runner import parse_slice, selected_count

    assert selected_count(in_file, parse_slice(text)) == expected
