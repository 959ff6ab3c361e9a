"""``--scans`` has one grammar and one parser in every command: ``N`` the first N scans,
``START:STOP[:STEP]`` a Python slice of scan indices; what a command reports says which
scans it used."""

from __future__ import annotations

import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cli_helpers import all_commands, scanlines
from scanlines.data import sample
from scanlines.errors import ParameterError
from scanlines.reader_options import SCANS_HELP, parse_scans, select_scans
from scanlines.runs.runner import measured_scans

LOG_LENGTH = 60


def selected(text: str, length: int = LOG_LENGTH) -> list[int]:
    indexed = ((k, None) for k in range(length))
    return [k for k, _ in select_scans(indexed, parse_scans(text))]


@given(st.integers(1, 200))
def test_n_is_the_first_n_scans(n) -> None:
    assert selected(str(n)) == list(range(LOG_LENGTH))[:n]


@given(st.integers(0, 80), st.integers(1, 100), st.one_of(st.none(), st.integers(1, 7)))
def test_a_slice_selects_as_python_does(start, length, step) -> None:
    stop = start + length
    text = f"{start}:{stop}" + ("" if step is None else f":{step}")
    assert selected(text) == list(range(LOG_LENGTH))[start:stop:step]


@pytest.mark.parametrize(
    ("text", "expected"),
    [(None, list(range(LOG_LENGTH))), ("", list(range(LOG_LENGTH))), (":", list(range(60))),
     ("7:8", [7]), ("::20", [0, 20, 40]), ("55:", [55, 56, 57, 58, 59]), (":3", [0, 1, 2])],
)  # fmt: skip
def test_the_open_forms(text, expected) -> None:
    assert selected(text) == expected


@pytest.mark.parametrize("text", ["0", "5:5", "9:3", "-1", "1:2:0", "a", "1:2:3:4", "1.5"])
def test_what_selects_nothing_or_is_not_the_grammar_is_refused(text) -> None:
    with pytest.raises(ParameterError, match="--scans"):
        parse_scans(text)


def test_every_command_that_takes_scans_says_the_one_grammar() -> None:
    """Walked from the application: each ``--scans`` is a text parsed by the one parser,
    its help the one sentence."""
    commands = all_commands()
    taking = {
        name: option
        for name, command in commands.items()
        for option in command.params
        if "--scans" in option.opts
    }
    assert {"run", "plot", "calibrate", "ros2", "map", "eval real", "eval map"} <= set(taking)
    for name, option in taking.items():
        assert SCANS_HELP in option.help, name


def test_measured_scans_names_the_scans() -> None:
    assert measured_scans(slice(None), 500) == "the first 500 scans"
    assert measured_scans(slice(0, 100), 100) == "the first 100 scans"
    assert measured_scans(slice(100, 200), 100) == "scans 100-199"
    assert measured_scans(slice(0, 300, 10), 30) == "30 scans (0, 10, ..., 290)"


def test_run_of_a_slice_says_which_scans_the_profile_came_from() -> None:
    out = scanlines("run", sample("freiburg"), "--scans", "100:200")
    assert out.returncode == 0, out.stderr
    assert "sensor profile: measured from scans 100-199 of fr079_excerpt.log.gz" in out.stderr
    assert "the first 100 scans" not in out.stderr


def test_map_takes_a_slice_and_n(tmp_path) -> None:
    log = sample("intel")
    sliced = scanlines("map", log, "--scans", "100:160", "--out", tmp_path / "a.json")
    assert sliced.returncode == 0, sliced.stderr
    assert "of 60 scans" in sliced.stdout
    assert json.loads((tmp_path / "a.json").read_text())["scans"] == 60
    first = scanlines("map", log, "--scans", "40", "--out", tmp_path / "b.json")
    assert first.returncode == 0, first.stderr
    assert "of 40 scans" in first.stdout


def test_eval_real_takes_a_slice(tmp_path) -> None:
    out = scanlines("eval", "--real", sample("intel"), "--scans", "100:130", "--pairs", "4",
                    "-m", "iepf", "--out", tmp_path / "e")  # fmt: skip
    assert out.returncode == 0, out.stderr
    (row,) = json.loads((tmp_path / "e" / "repeatability.json").read_text())
    assert row["scans"] <= 30


def test_calibrate_of_a_slice(tmp_path) -> None:
    out = scanlines("calibrate", sample("intel"), "--scans", "::3", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads((tmp_path / "intel_excerpt.profile.json").read_text())["scans"] == 100
