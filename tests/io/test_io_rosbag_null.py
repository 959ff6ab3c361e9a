"""ROS 2 ``.db3`` bags with NULL in their tables (a damaged database): a clean error or a
listed, skipped topic; never a traceback, never a silent loss."""

from __future__ import annotations

import shutil
import sqlite3
from itertools import islice
from pathlib import Path

import pytest
from bag_helpers import write_bag

from cli_helpers import Ran
from cli_helpers import scanlines as run_in_process
from scanlines.data import sample
from scanlines.errors import LogFormatError
from scanlines.io import open_log


@pytest.fixture(scope="module")
def seed_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A sqlite3 bag of 5 scans on /scan and 5 strings on /notes."""
    path = tmp_path_factory.mktemp("seed") / "bag"
    write_bag(path, "sqlite3", list(islice(open_log(sample("intel")), 5)), string_topic="/notes")
    return path


def with_null(seed: Path, target: Path, table: str, column: str, where: str, meta: bool) -> Path:
    """A copy of ``seed`` with ``column`` of ``table`` set to NULL in the rows ``where``
    (the NOT NULL constraints dropped first, as damage would), with or without its
    ``metadata.yaml``."""
    shutil.copytree(seed, target)
    database = next(target.glob("*.db3"))
    with sqlite3.connect(database) as db:
        (sql,) = db.execute("SELECT sql FROM sqlite_master WHERE name = ?", (table,)).fetchone()
        db.execute(f"ALTER TABLE {table} RENAME TO old_{table}")
        db.execute(sql.replace("NOT NULL", ""))
        db.execute(f"INSERT INTO {table} SELECT * FROM old_{table}")
        db.execute(f"DROP TABLE old_{table}")
        db.execute(f"UPDATE {table} SET {column} = NULL WHERE {where}")
    if not meta:
        (target / "metadata.yaml").unlink()
    return target


def scanlines(*args: object) -> Ran:
    return run_in_process(*args)


@pytest.mark.parametrize("meta", [True, False])
def test_other_topic_without_a_name_is_listed_and_skipped(tmp_path, seed_bag, meta) -> None:
    path = with_null(seed_bag, tmp_path / "bag", "topics", "name", "name = '/notes'", meta)
    reader = open_log(path)
    assert len(list(reader)) == 5
    out = scanlines("info", path)
    assert out.returncode == 0, out.stderr
    assert "Traceback" not in out.stderr
    if not meta:
        assert "<topic 2 without a name> 5" in out.stdout


@pytest.mark.parametrize("meta", [True, False])
def test_laserscan_topic_without_a_name_is_an_error(tmp_path, seed_bag, meta) -> None:
    path = with_null(seed_bag, tmp_path / "bag", "topics", "name", "name = '/scan'", meta)
    with pytest.raises(LogFormatError) as caught:
        list(open_log(path))
    assert str(path) in str(caught.value)
    for command in ("info", "run"):
        out = scanlines(command, path, "--out", tmp_path / "out.jsonl")
        if command == "info":
            out = scanlines(command, path)
        assert out.returncode == 2, out.stderr
        lines = out.stderr.strip().splitlines()
        assert lines[-1].startswith(f"scanlines: error: {path}")
        assert "Traceback" not in out.stderr


@pytest.mark.parametrize(
    ("table", "column", "where"),
    [
        ("topics", "type", "name = '/scan'"),
        ("topics", "type", "name = '/notes'"),
        ("topics", "serialization_format", "1"),
        ("topics", "offered_qos_profiles", "1"),
        ("messages", "data", "id = 3"),
        ("messages", "timestamp", "id = 3"),
        ("messages", "topic_id", "id = 3"),
    ],
)
@pytest.mark.parametrize("meta", [True, False])
def test_null_fields_are_read_or_refused_cleanly(
    tmp_path, seed_bag, table, column, where, meta
) -> None:
    path = with_null(seed_bag, tmp_path / "bag", table, column, where, meta)
    for on_error in ("fail", "skip"):
        error = None
        try:
            reader = open_log(path, on_error=on_error)
            scans = list(reader)
        except LogFormatError as raised:
            error = str(raised)
        if error is not None:
            assert str(path) in error
            assert len(error.splitlines()) == 1
        else:
            assert len(scans) + reader.bad_scans == reader.info()["scans_in_file"]
