"""`scanlines map --align`, `localize` and `eval map` on the shipped Intel excerpt write exactly
what ``tests/records/map_outputs.json`` records, timings aside.

The record holds each output's SHA-256 (a JSON file with its ``seconds`` fields dropped,
the rest as written) and, in full, the settings the map and the score record (``fusion``,
``tracking``): moving the map's settings tables to :class:`scanlines.params.tables.SettingsTable`
changed none of them. It was made on Linux x86-64 before that change
(``python tests/test_map_records.py``); a change meant to change a map, a trajectory or a
score re-records it in its own commit and says why.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

pytest.importorskip("scipy")  # map --align closes loops with it; without it the map differs

from scanlines.cli.commands import app
from scanlines.data import sample

RECORD = Path(__file__).parent / "records" / "map_outputs.json"
TIMINGS = {"seconds"}
"""Keys of the JSON outputs that hold a time measured, not computed."""

COMMANDS = (
    ("map", "{log}", "--align", "--out", "{out}/map.json", "--poses-out", "{out}/poses.tum"),
    ("map", "{log}", "--out", "{out}/plain.json", "--min-scans", "2"),
    ("localize", "{log}", "--map", "{out}/map.json", "--out", "{out}/found.tum"),
    ("localize", "{log}", "--map", "{out}/map.json", "--out", "{out}/started.tum",
     "--initial-pose-from", "{out}/poses.tum"),
    ("eval", "map", "{log}", "--align", "--out", "{out}/aligned"),
    ("eval", "map", "{log}", "--out", "{out}/given"),
)  # fmt: skip
OUTPUTS = (
    "map.json", "poses.tum", "poses.cov.json", "plain.json", "found.tum", "found.cov.json",
    "started.tum", "started.cov.json", "aligned/map_eval.json", "given/map_eval.json",
)  # fmt: skip


def untimed(value):
    """A JSON value without its timing fields."""
    if isinstance(value, dict):
        return {k: untimed(v) for k, v in value.items() if k not in TIMINGS}
    if isinstance(value, list):
        return [untimed(v) for v in value]
    return value


def digest(path: Path) -> str:
    data = path.read_bytes()
    if path.suffix == ".json":
        data = json.dumps(untimed(json.loads(data)), indent=1).encode()
    return hashlib.sha256(data).hexdigest()


def run_commands(out: Path) -> dict:
    """Run the commands into ``out``: the digests of their outputs and the settings they
    record."""
    log = sample("intel")
    for command in COMMANDS:
        args = [part.format(log=log, out=out) for part in command]
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 0, (args, result.output)
    built = json.loads((out / "map.json").read_text())
    plain = json.loads((out / "plain.json").read_text())
    scored = json.loads((out / "aligned" / "map_eval.json").read_text())
    return {
        "settings": {
            "map --align: fusion": built["fusion"],
            "map --align: tracking": built["tracking"]["settings"],
            "map --min-scans 2: fusion": plain["fusion"],
            "eval map --align: tracking": scored["tracking"],
        },
        "digests": {name: digest(out / name) for name in OUTPUTS},
    }


@pytest.fixture(scope="module")
def current(tmp_path_factory):
    return run_commands(tmp_path_factory.mktemp("map_records"))


@pytest.fixture(scope="module")
def recorded():
    return json.loads(RECORD.read_text())


def test_the_settings_written_are_the_recorded_ones(current, recorded):
    assert current["settings"] == recorded["settings"]


@pytest.mark.parametrize("name", OUTPUTS)
def test_each_output_is_the_recorded_one(current, recorded, name):
    assert current["digests"][name] == recorded["digests"][name], name


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        record = run_commands(Path(folder))
    RECORD.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {RECORD}", file=sys.stderr)
