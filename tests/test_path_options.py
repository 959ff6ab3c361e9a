"""Every path option of every command, walked from the command line application itself:
a file it reads that is not there is ``PATH: no such file or directory`` (one line, exit
2, no ``[Errno 2]``), whatever the option; ``--method`` unknown is one line naming the
methods; ``extract`` on a log says it is a log."""

from __future__ import annotations

import inspect
import os
import typing
from pathlib import Path

import pytest
import typer

from cli_helpers import all_commands, scanlines
from scanlines.cli.common import OUTPUT_PARAMETERS, os_error_line
from scanlines.data import sample

INTEL = sample("intel")
NO_SUCH_FILE = "no such file or directory"


def _is_path(annotation) -> bool:
    if typing.get_origin(annotation) is typing.Annotated:
        annotation = typing.get_args(annotation)[0]
    return annotation is Path or any(_is_path(a) for a in typing.get_args(annotation))


def commands() -> dict:
    return all_commands()


def path_parameters(command) -> list[str]:
    """The parameters of a command typed as a path (or a list of paths)."""
    hints = typing.get_type_hints(inspect.unwrap(command.callback), include_extras=True)
    return [name for name, hint in hints.items() if name != "return" and _is_path(hint)]


def input_options() -> list[tuple[str, str]]:
    """``(command, parameter)`` of every path a command reads."""
    return [
        (name, parameter)
        for name, command in commands().items()
        for parameter in path_parameters(command)
        if parameter not in OUTPUT_PARAMETERS
    ]


def invocation(command_name: str, missing_parameter: str, missing: Path, tmp: Path) -> list:
    """The command with every required parameter given (files that exist, outputs in
    ``tmp``) and ``missing_parameter`` naming ``missing``."""
    words: list = command_name.split()
    for parameter in commands()[command_name].params:
        given = parameter.name == missing_parameter
        if not (given or parameter.required):
            continue
        if parameter.name in OUTPUT_PARAMETERS:
            value = tmp / f"{parameter.name}.json"
        elif given:
            value = missing
        else:
            value = INTEL
        if isinstance(parameter, typer.core.TyperArgument):
            words.append(value)
        else:
            words += [parameter.opts[0], value]
    return words


def test_the_walk_finds_the_inputs_of_every_kind() -> None:
    found = set(input_options())
    for expected in [
        ("localize", "map_file"),
        ("localize", "initial_pose_from"),
        ("map", "poses"),
        ("eval trajectory", "estimate"),
        ("eval trajectory", "reference"),
        ("eval real", "logs"),
        ("eval map", "poses"),
        ("run", "logs"),
        ("extract", "sensor_profile"),
        ("view", "config"),
        ("ros2", "play"),
    ]:
        assert expected in found
    assert len(found) >= 25


@pytest.mark.parametrize(("command", "parameter"), input_options())
def test_a_missing_input_is_one_line_in_one_form(command, parameter, tmp_path) -> None:
    missing = tmp_path / "nowhere" / f"{parameter}.x"
    out = scanlines(*invocation(command, parameter, missing, tmp_path), cwd=tmp_path)
    assert out.returncode == 2, (out.stdout, out.stderr)
    assert out.stderr.strip().splitlines() == [f"scanlines: error: {missing}: {NO_SUCH_FILE}"]
    assert "Errno" not in out.stderr


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file whatever its mode")
def test_an_unreadable_input_is_one_line(tmp_path) -> None:
    locked = tmp_path / "locked.tum"
    locked.write_text("0 0 0 0 0 0 0 1\n")
    locked.chmod(0)
    out = scanlines("map", INTEL, "--poses", locked, "--out", tmp_path / "m.json")
    assert out.stderr.strip().splitlines() == [f"scanlines: error: {locked}: permission denied"]


def test_an_input_that_is_a_folder_is_one_line_without_errno(tmp_path) -> None:
    folder = tmp_path / "poses.tum"
    folder.mkdir()
    out = scanlines("map", INTEL, "--poses", folder, "--out", tmp_path / "m.json")
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [f"scanlines: error: {folder}: is a directory"]


def test_an_os_error_reads_path_colon_reason() -> None:
    error = FileNotFoundError(2, "No such file or directory", "x.tum")
    assert os_error_line(error) == "x.tum: no such file or directory"
    assert os_error_line(OSError("the disk said no")) == "the disk said no"


def method_commands() -> list[str]:
    """Commands whose ``--method`` names one extraction method."""
    return [
        name
        for name, command in commands().items()
        for parameter in command.params
        if "--method" in parameter.opts and not parameter.multiple
    ]


@pytest.mark.parametrize("command", method_commands())
def test_an_unknown_method_is_one_line_naming_the_methods(command, tmp_path) -> None:
    words = [command, "--method", "foo"]
    if command in ("extract", "info", "run", "calibrate", "plot", "view", "map"):
        words.insert(1, INTEL)
    if command == "plot":
        words += ["--scan", "0"]
    if command == "map":
        words += ["--out", tmp_path / "m.json"]
    out = scanlines(*words, cwd=tmp_path)
    assert out.returncode == 2
    (line,) = out.stderr.strip().splitlines()
    assert line.startswith("scanlines: error: --method 'foo' is not a method; methods: ")
    assert all(name in line for name in ("adaptive", "iepf", "surfaces"))


def test_the_method_commands_are_the_extracting_ones() -> None:
    assert {"extract", "run", "plot", "map", "view", "ros2"} <= set(method_commands())


def test_extract_on_a_log_says_it_is_a_log() -> None:
    out = scanlines("extract", INTEL)
    assert out.returncode == 2
    (line,) = out.stderr.strip().splitlines()
    assert "a CARMEN log, not a single scan" in line
    assert "angle_min" not in line
    assert "scanlines plot LOG --scan N" in line
