"""Parameters files, ``-p`` values, configuration files and sensor profiles read at a
bounded cost: a YAML alias bomb, a recursive alias, 100 KB of nested ``[``, an integer of
5,000 digits, ``/dev/zero``, a FIFO and an oversized profile are each refused in one line
(exit 2) that quotes at most 80 characters of the value, in well under a second."""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("yaml")

from cli_helpers import scanlines
from scanlines.config import load_config
from scanlines.data import sample
from scanlines.errors import ParameterError
from scanlines.methods import method_class
from scanlines.ros2.dds import ros_topic
from scanlines.ros2.ros_args import parse_ros_args
from scanlines.sensor.profile import ProfileError, SensorProfile, read_profile
from scanlines.sensor.profile_file import MAX_PROFILE_BYTES
from scanlines.untrusted import QUOTED, UntrustedInput, json_depth, load_json, load_yaml, quote

#: The longest error line a refused input may give (its value quoted in 80 characters).
MAX_LINE = 400


def alias_bomb(levels: int = 8) -> str:
    """A parameters file whose ``min_points`` expands to 9**levels strings: the anchors
    sit in another node's section, which this node ignores (414 bytes at 8 levels)."""
    rows = ['    a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    names = "abcdefghij"
    for k in range(1, levels):
        alias = f"*{names[k - 1]}"
        rows.append(f"    {names[k]}: &{names[k]} [{','.join([alias] * 9)}]")
    body = "\n".join(rows)
    tail = f"scanlines:\n  ros__parameters:\n    min_points: *{names[levels - 1]}\n"
    return f"other:\n  ros__parameters:\n{body}\n{tail}"


def written(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def refused(done, *words: str) -> str:
    """The one error line of a command that must have refused its input with exit 2."""
    assert done.returncode == 2, done.stderr[-2000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, lines[:5]
    (line,) = lines
    assert line.startswith("scanlines: error: "), line[:200]
    assert len(line) <= MAX_LINE, line[:200]
    for word in words:
        assert word in line, line
    return line


def ros2_params(tmp_path: Path, text: str):
    path = tmp_path / "params.yaml"
    path.write_text(text)
    return scanlines("ros2", "--loopback", "--ros-args", "--params-file", path)


# -- parameters files (YAML) -------------------------------------------------------------


def test_a_454_byte_alias_bomb_is_refused_in_one_line_at_once(tmp_path):
    bomb = alias_bomb()
    assert len(bomb) <= 454  # the audit's bomb: 454 bytes
    started = time.perf_counter()
    line = refused(ros2_params(tmp_path, bomb), "params.yaml", "aliases are expanded")
    assert time.perf_counter() - started < 5.0  # 6 s and 488 MB before, 140 MB of stderr
    assert "100000 values" in line


def test_a_recursive_alias_is_refused_in_one_line(tmp_path):
    text = "scanlines:\n  ros__parameters: &a\n    nested: *a\n"
    refused(ros2_params(tmp_path, text), "params.yaml", "recursive alias")
    done = scanlines("ros2", "--loopback", "--ros-args", "-p", "min_points:=&a [*a]")
    refused(done, "min_points", "recursive alias")


def test_100_kb_of_nested_brackets_is_refused_in_one_line(tmp_path):
    deep = "[" * 100_000
    refused(
        ros2_params(tmp_path, f"scanlines:\n  ros__parameters:\n    k: {deep}\n"), "params.yaml"
    )
    line = refused(scanlines("ros2", "--loopback", "--ros-args", "-p", f"min_points:={deep}"))
    assert "min_points" in line


def test_an_integer_of_5000_digits_is_refused_in_one_line(tmp_path):
    digits = "1" * 5000
    done = scanlines("ros2", "--loopback", "--ros-args", "-p", f"min_points:={digits}")
    refused(done, "min_points", "5000 characters (at most 100 digits)")
    text = f"scanlines:\n  ros__parameters:\n    min_points: {digits}\n"
    refused(ros2_params(tmp_path, text), "params.yaml", "at most 100 digits")


def test_a_long_value_is_quoted_in_at_most_80_characters(tmp_path):
    long = "x" * 5000
    line = refused(scanlines("ros2", "--loopback", "--ros-args", "-p", f"min_points:={long}"))
    assert "x" * QUOTED not in line
    assert "min_points" in line
    text = f"scanlines:\n  ros__parameters:\n    min_points: [{', '.join(['1'] * 5000)}]\n"
    refused(ros2_params(tmp_path, text), "params.yaml", "min_points")


@pytest.mark.parametrize("special", ["/dev/zero", "fifo"])
def test_a_special_file_as_parameters_file_is_refused(tmp_path, special):
    path = Path(special) if special != "fifo" else tmp_path / "fifo"
    if special == "fifo":
        os.mkfifo(path)
    with pytest.raises(ParameterError, match="not a regular file"):
        parse_ros_args(["--params-file", str(path)]).parameters()


def test_a_parameters_file_with_an_anchor_and_its_alias_still_loads(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(
        "common:\n  ros__parameters: &defaults\n    min_length: 0.2\n"
        "/**/scanlines:\n  ros__parameters:\n    <<: *defaults\n    min_points: 7\n"
    )
    values = parse_ros_args(["--params-file", str(path)]).parameters()
    assert values["min_length"].value == 0.2
    assert values["min_points"].value == 7


@pytest.mark.parametrize(
    "call",
    [
        lambda name, folder: load_config(written(folder / "c.toml", f"method = '{name}'\n")),
        lambda name, folder: method_class(name),
        lambda name, folder: ros_topic(name + "!"),
    ],
    ids=["configuration's method", "method name", "topic name"],
)
def test_a_long_name_is_quoted_in_at_most_80_characters(call, tmp_path):
    with pytest.raises(ParameterError) as caught:
        call("x" * 1200, tmp_path)
    assert "x" * QUOTED not in str(caught.value)
    assert len(str(caught.value)) <= MAX_LINE


# -- configuration files (TOML) ------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("[params]\nmin_points = " + "[" * 100_000, "nested too deep"),
        ("params = " + "{a=" * 30_000 + "1" + "}" * 30_000, "nested too deep"),
        ("[params]\nmin_points = " + "1" * 5000, "4300 digits"),
    ],
    ids=["nested arrays", "nested tables", "5000 digits"],
)
def test_a_hostile_configuration_is_one_config_error(tmp_path, text, reason):
    path = tmp_path / "c.toml"
    path.write_text("method = 'iepf'\n" + text)
    with pytest.raises(ParameterError, match=reason) as caught:
        load_config(path)
    assert len(str(caught.value)) <= MAX_LINE
    done = scanlines("run", sample("intel"), "--config", path, "--out", tmp_path / "o.jsonl")
    refused(done, "c.toml")


# -- sensor profiles -------------------------------------------------------------------------


def profile_values(**changes) -> dict:
    values = SensorProfile(0.004, 0.001, beams=180, scans=10, source="test").to_dict()
    return {**values, **changes}


def run_in_a_process(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess:
    """``scanlines ARGS`` in a process of its own, its address space limited to 3 GB (so
    reading ``/dev/zero`` whole fails quickly rather than filling the machine)."""

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))

    return subprocess.run(
        [sys.executable, "-m", "scanlines", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        preexec_fn=limit,
        check=False,
    )


def test_run_refuses_dev_zero_as_a_sensor_profile_in_one_line(tmp_path):
    done = run_in_a_process(
        "run", str(sample("intel")), "--sensor-profile", "/dev/zero",
        "--out", str(tmp_path / "o.jsonl"),
    )  # fmt: skip
    refused(done, "/dev/zero", "not a regular file (a character device)")


def test_the_node_refuses_dev_zero_as_its_sensor_profile_in_one_line():
    done = run_in_a_process("ros2", "--loopback", "--ros-args", "-p", "sensor_profile:=/dev/zero")
    refused(done, "/dev/zero", "not a regular file")


def test_a_fifo_as_a_sensor_profile_is_refused_without_waiting(tmp_path):
    fifo = tmp_path / "profile.json"
    os.mkfifo(fifo)
    started = time.perf_counter()
    with pytest.raises(ProfileError, match="a FIFO"):
        read_profile(fifo)
    assert time.perf_counter() - started < 5.0


def test_an_oversized_profile_is_refused_in_one_line(tmp_path):
    path = tmp_path / "big.json"
    path.write_text(json.dumps(profile_values(source="x" * MAX_PROFILE_BYTES)))
    with pytest.raises(ProfileError, match=f"larger than {MAX_PROFILE_BYTES} bytes"):
        read_profile(path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[" * 100_000, "nested more than 64 deep"),
        ('{"format": ' + "1" * 5000 + "}", "4300 digits"),
        (json.dumps(profile_values(noise_sigma0="x" * 5000)), "must be a number, got 'xxx"),
        (json.dumps(profile_values(noise_sigma0=True)), "must be a number, got True"),
        (json.dumps(profile_values(noise_bins=[{"range": [1] * 999}])), "noise bin 0"),
        (json.dumps(profile_values(mounting=[1, 2])), "mounting"),
        (json.dumps(profile_values(beams="many")), "'beams' must be a count"),
    ],
    ids=["nested", "5000 digits", "long string", "boolean", "bad bin", "mounting", "beams"],
)
def test_a_hostile_profile_is_one_profile_error(tmp_path, text, message):
    path = tmp_path / "p.json"
    path.write_text(text)
    with pytest.raises(ProfileError, match=message) as caught:
        read_profile(path)
    assert len(str(caught.value)) <= MAX_LINE


# -- the helpers -------------------------------------------------------------------------------


def test_quote_never_expands_a_huge_or_nested_value():
    nested: list = []
    nested.append(nested)
    for value in ["x" * 10**6, 10**5000, [[[[[[1]]]]]] * 1000, nested, {"k" * 999: 1}]:
        assert len(quote(value)) <= QUOTED
    assert quote(10**5000) == "<an integer of 5001 digits>"
    assert quote("abc") == "'abc'"
    assert quote(1.5) == "1.5"


def test_yaml_limits_are_counted_not_expanded():
    with pytest.raises(UntrustedInput, match="aliases are expanded"):
        load_yaml(alias_bomb(levels=9))
    assert load_yaml("a: &x [1, 2]\nb: *x") == {"a": [1, 2], "b": [1, 2]}
    assert load_yaml("k: " + "9" * 100) == {"k": int("9" * 100)}


def test_json_depth_skips_strings():
    assert json_depth('{"a": "[[[[", "b": [[1]], "c": "\\"["}') == 3
    assert load_json("[" * 64 + "]" * 64) is not None
    with pytest.raises(UntrustedInput, match="nested more than 64 deep"):
        load_json("[" * 65 + "]" * 65)
