"""``scanlines run LOG --out x.rrd``: a Rerun recording of the scans and their features,
read back with the Rerun SDK and compared with a JSON Lines run of the same scans."""

from __future__ import annotations

import json
import subprocess
import sys
from datetime import UTC, datetime
from itertools import islice

import numpy as np
import pytest

import scanlines
from scanlines.data import sample
from scanlines.errors import ParameterError
from scanlines.extraction import Extraction
from scanlines.io import RerunWriter, meta_path_for, open_log, open_writer, points_to_world
from scanlines.outputs import OutputError
from test_cli_logs import one_error_line, run

pytest.importorskip("rerun")

ENTITIES = ("returns", "segments", "breakpoints", "corners", "outliers")
SCANS = 20


def read_rrd(path) -> dict[str, dict[int, dict]]:
    """Entity name (``segments``...) -> scan index -> that row's columns (the ``time``
    column, when the row has none, is ``None``); a scan logged twice is an error."""
    from rerun.chunk import RrdReader

    rows: dict[str, dict[int, dict]] = {}
    for chunk in RrdReader(path).stream():
        if chunk.is_static:
            continue
        entity = chunk.entity_path.removeprefix("/scan/")
        columns = chunk.to_record_batch().to_pydict()
        for k, index in enumerate(columns["scan"]):
            row = {name.split(":")[-1]: values[k] for name, values in columns.items()}
            row.setdefault("time", None)
            assert index not in rows.setdefault(entity, {}), f"scan {index} twice in {entity}"
            rows[entity][index] = row
    return rows


def seconds(moment: datetime) -> float:
    return moment.replace(tzinfo=UTC).timestamp()


@pytest.fixture(scope="module")
def intel_runs(tmp_path_factory):
    """The first 20 Intel scans as ``x.rrd`` and ``x.jsonl``, same options."""
    folder = tmp_path_factory.mktemp("rrd")
    for name in ("x.rrd", "x.jsonl"):
        out = run("run", sample("intel"), "--scans", f"0:{SCANS}", "--out", folder / name)
        assert out.returncode == 0, out.stderr
    records = [json.loads(line) for line in (folder / "x.jsonl").read_text().splitlines()]
    return folder / "x.rrd", records


def test_rrd_holds_every_scan_on_the_scan_and_time_timelines(intel_runs) -> None:
    path, records = intel_runs
    rows = read_rrd(path)
    assert sorted(rows) == sorted(ENTITIES)
    for entity in ENTITIES:
        assert sorted(rows[entity]) == list(range(SCANS)), entity
    for record in records:
        row = rows["segments"][record["scan"]]
        assert seconds(row["time"]) == pytest.approx(record["timestamp"], abs=2e-6)


def test_rrd_features_equal_the_jsonl_features(intel_runs) -> None:
    path, records = intel_runs
    rows = read_rrd(path)
    assert len(records) == SCANS
    assert sum(len(r["segments"]) for r in records) > SCANS  # something to compare
    for record in records:
        index, segments = record["scan"], record["segments"]
        strips = np.array(rows["segments"][index]["strips"], dtype=float).reshape(-1, 2, 2)
        expected = np.array([[s["start"], s["end"]] for s in segments]).reshape(-1, 2, 2)
        assert strips.shape == expected.shape, index
        np.testing.assert_allclose(strips, expected, rtol=1e-6, atol=1e-6)
        colors = rows["segments"][index]["colors"]
        assert len(colors) == len(segments) == len(set(colors)), index  # one each, distinct
        for entity in ("breakpoints", "corners"):
            assert len(rows[entity][index]["positions"]) == len(record[entity]), (entity, index)


def test_rrd_returns_are_the_valid_beams(intel_runs) -> None:
    path, _ = intel_runs
    rows = read_rrd(path)
    for index, scan in enumerate(islice(open_log(sample("intel")), SCANS)):
        returns = np.array(rows["returns"][index]["positions"])
        np.testing.assert_allclose(returns, scan.points[scan.valid], rtol=1e-6, atol=1e-6)


def test_rrd_has_its_meta_and_is_not_replaced_without_overwrite(intel_runs) -> None:
    path, _ = intel_runs
    meta = json.loads(meta_path_for(path).read_text())
    assert meta["output_format"] == "rerun"
    assert meta["output"] == "x.rrd"
    assert meta["counts"]["scans"] == SCANS
    before = path.stat().st_mtime_ns, path.stat().st_size
    out = run("run", sample("intel"), "--scans", "0:2", "--out", path)
    one_error_line(out, "exists")
    assert (path.stat().st_mtime_ns, path.stat().st_size) == before


def test_world_frame_moves_segments_and_returns(tmp_path) -> None:
    for name in ("w.rrd", "w.jsonl"):
        out = run(
            "run", sample("intel"), "--scans", "0:5", "--frame", "world", "--out", tmp_path / name
        )
        assert out.returncode == 0, out.stderr
    rows = read_rrd(tmp_path / "w.rrd")
    records = [json.loads(line) for line in (tmp_path / "w.jsonl").read_text().splitlines()]
    assert json.loads(meta_path_for(tmp_path / "w.rrd").read_text())["frame"] == "world"
    for record, scan in zip(records, islice(open_log(sample("intel")), 5), strict=True):
        strips = np.array(rows["segments"][record["scan"]]["strips"]).reshape(-1, 2, 2)
        expected = np.array([[s["start"], s["end"]] for s in record["segments"]]).reshape(-1, 2, 2)
        np.testing.assert_allclose(strips, expected, rtol=1e-6, atol=1e-5)
        returns = np.array(rows["returns"][record["scan"]]["positions"])
        world = points_to_world(scan.points[scan.valid], scan.pose)
        np.testing.assert_allclose(returns, world, rtol=1e-6, atol=1e-5)
        assert not np.allclose(world, scan.points[scan.valid], atol=0.1)  # really moved


@pytest.fixture(scope="module")
def intel_scans():
    scans = list(islice(open_log(sample("intel")), 3))
    return scans, [scanlines.extract(scan) for scan in scans]


def nothing(extraction: Extraction) -> Extraction:
    """An extraction of the same method without any feature."""
    empty = np.empty(0, dtype=int)
    return Extraction(
        first=empty,
        last=empty,
        n_points=empty,
        lines=np.empty((0, 7)),
        covariances=np.empty((0, 2, 2)),
        breakpoints=empty,
        corners=empty,
        outliers=empty,
        method=extraction.method,
        params=extraction.params,
    )


def test_empty_features_clear_the_previous_scans(tmp_path, intel_scans) -> None:
    (scan, *_), (extraction, *_) = intel_scans
    assert min(len(extraction), len(extraction.breakpoints), len(extraction.corners)) > 0
    with open_writer(tmp_path / "x.rrd") as writer:
        writer.write(0, scan, extraction)
        writer.write(1, scan, nothing(extraction))
    rows = read_rrd(tmp_path / "x.rrd")
    assert len(rows["segments"][0]["strips"]) == len(extraction)
    assert rows["segments"][1]["strips"] == []
    assert rows["breakpoints"][1]["positions"] == rows["corners"][1]["positions"] == []
    assert len(rows["returns"][1]["positions"]) == int(scan.valid.sum())


def test_a_scan_without_time_is_only_on_the_scan_timeline(tmp_path, intel_scans) -> None:
    (scan, *_), (extraction, *_) = intel_scans
    untimed = scanlines.Scan(
        scan.ranges,
        scan.angle_min,
        scan.angle_increment,
        range_min=scan.range_min,
        range_max=scan.range_max,
        timestamp=None,
    )
    with open_writer(tmp_path / "x.rrd") as writer:
        writer.write(0, scan, extraction)
        writer.write(1, untimed, extraction)
    rows = read_rrd(tmp_path / "x.rrd")["corners"]
    assert seconds(rows[0]["time"]) == pytest.approx(scan.timestamp, abs=2e-6)
    assert rows[1]["time"] is None


def write_then_fail(path, scans, extractions, *, frame="sensor", overwrite=False) -> None:
    with open_writer(path, frame=frame, overwrite=overwrite) as writer:
        assert isinstance(writer, RerunWriter)
        writer.write(0, scans[0], extractions[0])
        if frame == "world":  # a scan without a pose: the writer raises
            writer.write(
                1,
                scanlines.Scan(scans[1].ranges, scans[1].angle_min, scans[1].angle_increment),
                extractions[1],
            )
        writer.write(1, scans[1], extractions[1])
        raise RuntimeError("boom")


def test_a_failed_write_leaves_nothing(tmp_path, intel_scans) -> None:
    scans, extractions = intel_scans
    with pytest.raises(RuntimeError, match="boom"):
        write_then_fail(tmp_path / "x.rrd", scans, extractions)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ParameterError, match="needs scan poses"):
        write_then_fail(tmp_path / "x.rrd", scans, extractions, frame="world")
    assert list(tmp_path.iterdir()) == []


def test_an_existing_rrd_is_kept_until_a_write_succeeds(tmp_path, intel_scans) -> None:
    scans, extractions = intel_scans
    path = tmp_path / "x.rrd"
    with open_writer(path) as writer:
        writer.write(0, scans[0], extractions[0])
    before = {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()}
    assert sorted(before) == ["x.rrd", "x.rrd.meta.json"]
    with pytest.raises(OutputError, match="exists; not replacing it"):
        open_writer(path)
    with pytest.raises(RuntimeError, match="boom"):
        write_then_fail(path, scans, extractions, overwrite=True)
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()} == before
    with open_writer(path, overwrite=True) as writer:
        for index, (scan, extraction) in enumerate(zip(scans, extractions, strict=True)):
            writer.write(index, scan, extraction)
    assert sorted(read_rrd(path)["segments"]) == [0, 1, 2]
    assert json.loads(meta_path_for(path).read_text())["counts"]["scans"] == 3


def test_missing_sdk_is_one_line_naming_the_extra(tmp_path, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "rerun", None)
    with pytest.raises(ParameterError) as error:
        open_writer(tmp_path / "x.rrd")
    message = str(error.value)
    assert "\n" not in message
    assert 'pip install "scanlines[rerun]"' in message
    assert list(tmp_path.iterdir()) == []


def test_missing_sdk_stops_run_before_any_work(tmp_path) -> None:
    argv = ["scanlines", "run", str(sample("intel")), "--out", str(tmp_path / "x.rrd")]
    code = (
        "import runpy, sys; sys.modules['rerun'] = None; "
        f"sys.argv = {argv!r}; runpy.run_module('scanlines', run_name='__main__')"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    one_error_line(out, "scanlines[rerun]")
    assert "sensor profile" not in out.stderr  # stopped before reading the log
    assert list(tmp_path.iterdir()) == []


def test_importing_scanlines_io_does_not_import_rerun() -> None:
    code = "import sys, scanlines.io; print('rerun' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_several_logs_give_one_recording_each(tmp_path) -> None:
    (tmp_path / "recordings").mkdir()
    out = run(
        "run", sample("intel"), sample("urg"), "--scans", "0:5", "--format", "rrd",
        "--out", tmp_path / "recordings", "-j", "1",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    for name in ("intel_excerpt.clf.gz", "urg_excerpt.dat.gz"):
        recorded = read_rrd(tmp_path / "recordings" / f"{name}.rrd")
        assert sorted(recorded["segments"]) == list(range(5)), name
