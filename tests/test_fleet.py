"""Many logs at once: a Parquet dataset, local processes or a real Dask LocalCluster.

The logs: copies of the shipped Intel and Freiburg excerpts (CARMEN, two flavours) and an
MCAP bag written from the Intel excerpt by ``scanlines run``, split in chunks of 120
records so every log spreads over several tasks. The dataset is read back with DuckDB.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import duckdb
import pytest
from distributed import Client, LocalCluster

from scanlines.data import sample
from scanlines.runs.fleet import run_fleet

pytestmark = pytest.mark.slow  # a Dask LocalCluster per test

CHUNK = 120
SEGMENT_QUERY = """
    select log, scan, segment, first, last, rho, alpha, var_rho, start_kind, end_kind
    from read_parquet('{dataset}/segments/*/*.parquet', hive_partitioning = true)
    order by log, scan, segment
"""


def cli(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "scanlines", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, "COLUMNS": "200"},
    )


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("fleet") / "logs"
    for copy in ("a", "b"):
        (folder / copy).mkdir(parents=True)
        shutil.copy(sample("intel"), folder / copy)
        shutil.copy(sample("freiburg"), folder / copy)
    out = cli("run", sample("intel"), "--out", folder / "a" / "intel.mcap")
    assert out.returncode == 0, out.stderr
    (folder / "a" / "intel.mcap.meta.json").unlink()
    return folder


def segment_rows(dataset: Path) -> list[tuple]:
    return duckdb.connect().execute(SEGMENT_QUERY.format(dataset=dataset)).fetchall()


@pytest.fixture(scope="module")
def local_dataset(logs, tmp_path_factory) -> Path:
    dataset = tmp_path_factory.mktemp("local") / "features"
    summary = run_fleet([logs], dataset, jobs=2, chunk_records=CHUNK)
    assert not summary.failed
    assert [log.status for log in summary.logs] == ["done"] * 5
    return dataset


def test_rows_equal_those_of_single_log_runs(logs, local_dataset, tmp_path) -> None:
    rows = segment_rows(local_dataset)
    for log, name in (
        ("a__intel.mcap", "a/intel.mcap"),
        ("b__fr079_excerpt.log.gz", "b/fr079_excerpt.log.gz"),
    ):
        out = cli("run", logs / name, "--out", tmp_path / f"{log}.jsonl")
        assert out.returncode == 0, out.stderr
        records = [
            json.loads(line) for line in (tmp_path / f"{log}.jsonl").read_text().splitlines()
        ]
        expected = [
            (log, record["scan"], k, s["first"], s["last"], s["rho"], s["alpha"],
             s["covariance"][0][0], s["start_kind"], s["end_kind"])
            for record in records
            for k, s in enumerate(record["segments"])
        ]  # fmt: skip
        assert [row for row in rows if row[0] == log] == expected
        events = duckdb.connect().execute(
            f"select scan, kind, beam from read_parquet('{local_dataset}/events/log={log}/"
            "*.parquet') order by scan, kind, beam"
        ).fetchall()  # fmt: skip
        expected_events = sorted(
            (record["scan"], kind[:-1], beam)
            for record in records
            for kind in ("breakpoints", "corners")
            for beam in record[kind]
        )
        assert events == expected_events
        assert len(events) > 100


def test_a_local_cluster_gives_the_same_rows(logs, local_dataset, tmp_path) -> None:
    dataset = tmp_path / "features"
    summary = run_fleet([logs], dataset, jobs=2, scheduler="local", chunk_records=CHUNK)
    assert summary.engine.startswith("Dask LocalCluster")
    assert segment_rows(dataset) == segment_rows(local_dataset)


def test_a_killed_worker_loses_no_row_and_doubles_none(logs, local_dataset, tmp_path) -> None:
    dataset = tmp_path / "features"
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cluster,
        Client(cluster) as client,
    ):
        victims = list(client.run(os.getpid).values())
        killed = []

        def kill_one(result) -> None:
            if not killed:
                os.kill(victims[0], signal.SIGKILL)
                killed.append(victims[0])

        summary = run_fleet(
            [logs], dataset, scheduler=cluster.scheduler_address, chunk_records=CHUNK,
            on_chunk=kill_one,
        )  # fmt: skip
    assert killed
    assert not summary.failed
    assert segment_rows(dataset) == segment_rows(local_dataset)


def test_a_truncated_log_is_reported_and_the_others_finish(logs, tmp_path) -> None:
    mixed = tmp_path / "mixed"
    shutil.copytree(logs / "b", mixed)
    data = sample("intel").read_bytes()
    (mixed / "truncated.clf.gz").write_bytes(data[: len(data) // 2])
    out = cli("run", mixed, "--out", tmp_path / "features", "--format", "parquet", "-j", "2")
    assert out.returncode == 2, out.stderr
    assert "failed: truncated.clf.gz:" in out.stdout
    assert "truncated or corrupt" in out.stdout
    logs_written = {p.name for p in (tmp_path / "features" / "segments").iterdir()}
    assert logs_written == {"log=fr079_excerpt.log.gz", "log=intel_excerpt.clf.gz"}


def test_a_second_run_skips_finished_logs_and_refuses_other_parameters(logs, tmp_path) -> None:
    dataset = tmp_path / "features.parquet"
    first = cli("run", logs / "b", "--out", dataset, "-j", "1")
    assert first.returncode == 0, first.stderr
    parts = sorted(p.stat().st_mtime_ns for p in dataset.rglob("*.parquet"))
    again = cli("run", logs / "b", "--out", dataset, "-j", "1")
    assert again.returncode == 0, again.stderr
    assert "2 logs done before" in again.stdout
    assert sorted(p.stat().st_mtime_ns for p in dataset.rglob("*.parquet")) == parts
    other = cli("run", logs / "b", "--out", dataset, "--param", "k=4")
    assert other.returncode == 2
    assert "pass --overwrite" in other.stderr
    replaced = cli("run", logs / "b", "--out", dataset, "--param", "k=4", "--overwrite")
    assert replaced.returncode == 0, replaced.stderr


def test_duckdb_reads_the_dataset_with_the_documented_schema(local_dataset) -> None:
    con = duckdb.connect()
    columns = {
        table: [row[0] for row in con.execute(
            f"describe select * from read_parquet('{local_dataset}/{table}/*/*.parquet', "
            "hive_partitioning = true)"
        ).fetchall()]
        for table in ("segments", "events", "scans")
    }  # fmt: skip
    assert columns["segments"][:4] == ["scan", "segment", "timestamp", "method"]
    assert "covariance" not in columns["segments"]
    assert {"var_rho", "cov_rho_alpha", "var_alpha", "start_kind", "end_kind", "log"} <= set(
        columns["segments"]
    )
    assert columns["events"] == ["scan", "kind", "beam", "x", "y", "log"]
    assert {"pose_x", "beams", "segments", "corners", "log"} <= set(columns["scans"])
    per_log = dict(con.execute(
        f"select log, count(*) from read_parquet('{local_dataset}/scans/*/*.parquet', "
        "hive_partitioning = true) group by log"
    ).fetchall())  # fmt: skip
    assert per_log == dict.fromkeys(
        ["a__intel.mcap", "a__intel_excerpt.clf.gz", "a__fr079_excerpt.log.gz",
         "b__intel_excerpt.clf.gz", "b__fr079_excerpt.log.gz"], 300
    )  # fmt: skip
    import pyarrow.parquet as pq

    part = next((local_dataset / "segments").rglob("*.parquet"))
    meta = json.loads(pq.read_schema(part).metadata[b"scanlines"])
    assert meta["method"] == "adaptive"
    assert meta["params"]["k"] == 3.0


def test_several_logs_to_one_file_each(logs, tmp_path) -> None:
    out = cli("run", logs / "b" / "*.gz", "--out", tmp_path, "--format", "csv")
    assert out.returncode == 0, out.stderr
    assert sorted(p.name for p in tmp_path.glob("*.csv")) == [
        "fr079_excerpt.log.gz.csv", "intel_excerpt.clf.gz.csv"
    ]  # fmt: skip


def test_without_the_extra_the_message_names_it() -> None:
    code = (
        "import sys; sys.modules['pyarrow'] = None; sys.modules['distributed'] = None\n"
        "from scanlines.io.parquet import require_pyarrow\n"
        "try:\n    require_pyarrow()\nexcept Exception as e:\n    print(e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == (
        'Parquet output needs pyarrow: pip install ".[fleet]" in a scanlines checkout'
    )


def test_a_notebook_computes_the_tasks_on_its_own_cluster(logs, local_dataset, tmp_path) -> None:
    import dask

    from scanlines.runs.fleet import fleet_tasks

    dataset = tmp_path / "features"
    with (
        LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as cluster,
        Client(cluster),
    ):
        results = dask.compute(*fleet_tasks([logs / "b"], dataset, chunk_records=CHUNK))
    assert sum(result.scans for result in results) == 600
    expected = [row for row in segment_rows(local_dataset) if row[0].startswith("b__")]
    assert [row[1:] for row in segment_rows(dataset)] == [row[1:] for row in expected]


def test_a_changed_sensor_profile_is_not_taken_for_done(logs, tmp_path) -> None:
    from scanlines.io import open_log
    from scanlines.outputs import OutputError
    from scanlines.sensor.profile import estimate_profile

    profile = tmp_path / "sensor.json"
    estimate_profile(list(open_log(sample("intel")))).save(profile)
    log, dataset = logs / "b" / "intel_excerpt.clf.gz", tmp_path / "features"
    assert run_fleet([log], dataset, sensor_profile=profile).logs[0].status == "done"
    assert run_fleet([log], dataset, sensor_profile=profile).logs[0].status == "skipped"
    estimate_profile(list(open_log(sample("freiburg")))).save(profile)
    with pytest.raises(OutputError, match="--overwrite"):
        run_fleet([log], dataset, sensor_profile=profile)


def test_an_interrupted_run_starts_its_logs_again(logs, tmp_path) -> None:
    """Parts of a log whose run was interrupted (pending record, no finished one) are
    redone by the same command, and refused under other options."""
    log, dataset = logs / "b" / "intel_excerpt.clf.gz", tmp_path / "features"
    run_fleet([log], dataset, chunk_records=CHUNK)
    done = dataset / "_logs" / "intel_excerpt.clf.gz.json"
    record = json.loads(done.read_text())
    done.unlink()  # as if the run had stopped before the log's last task
    (dataset / "_logs" / "intel_excerpt.clf.gz.pending.json").write_text(json.dumps(record))
    rows = segment_rows(dataset)
    summary = run_fleet([log], dataset, chunk_records=CHUNK)
    assert summary.logs[0].status == "done"
    assert segment_rows(dataset) == rows
    done.unlink()
    from scanlines.outputs import OutputError

    with pytest.raises(OutputError, match="--overwrite"):
        run_fleet([log], dataset, params={"k": 4.0})


def test_an_interrupted_dask_run_shows_no_row_of_an_unfinished_log(logs, tmp_path) -> None:
    """Ctrl-C after the first of a log's three tasks: the log's parts stay staged, out of
    the documented query's sight, until a run finishes the log."""
    log, dataset = logs / "b" / "intel_excerpt.clf.gz", tmp_path / "features"

    def interrupt(result) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_fleet([log], dataset, jobs=1, scheduler="local", chunk_records=CHUNK,
                  on_chunk=interrupt)  # fmt: skip
    assert (dataset / "_logs" / "intel_excerpt.clf.gz.pending.json").exists()
    assert list((dataset / "_staging" / "segments").rglob("*.parquet"))
    assert segment_rows_or_none(dataset) == []
    summary = run_fleet([log], dataset, jobs=1, scheduler="local", chunk_records=CHUNK)
    assert summary.logs[0].status == "done"
    scans = (
        duckdb.connect()
        .execute(
            f"select count(*) from read_parquet('{dataset}/scans/*/*.parquet', "
            "hive_partitioning = true)"
        )
        .fetchone()
    )
    assert scans == (300,)
    assert not (dataset / "_staging").exists()


def segment_rows_or_none(dataset: Path) -> list[tuple]:
    """The documented query's rows; none when no table has a part yet."""
    if not list((dataset / "segments").glob("*/*.parquet")):
        return []
    return segment_rows(dataset)
