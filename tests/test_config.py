"""Extraction configurations: TOML files, dicts and command lines that give the same
configuration back, ``--config FILE`` on ``run``, ``extract`` and ``eval``, and its
errors (one line naming the file, exit code 2)."""

from __future__ import annotations

import csv
import json
import shlex
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import scanlines
from scanlines import Extractor, ParameterError, method_info
from scanlines.cli.common import method_options
from scanlines.config import ConfigError, ExtractionConfig, load_config
from scanlines.data import sample
from scenes import scan_of, square_room
from test_cli_logs import run as cli
from test_reliability import one_error_line

METHODS = scanlines.method_names()


# --------------------------------------------------------------------------- values


def floats(domain: dict) -> st.SearchStrategy:
    return st.floats(
        domain["low"],
        domain["high"],
        exclude_min=domain.get("low_open", False),
        allow_nan=False,
        allow_infinity=False,
    )


def values(domain: dict) -> st.SearchStrategy:
    """Every kind of value the domain takes (as the Python API takes it)."""
    kind = domain["type"]
    if kind == "choice":
        base = st.sampled_from(domain["choices"])
    elif kind == "int":
        base = st.integers(domain["low"], domain["high"])
    elif kind == "float":
        integral = st.integers(int(np.ceil(domain["low"])), int(domain["high"]))
        if domain.get("low_open"):
            integral = integral.filter(lambda v: v > domain["low"])
        base = st.one_of(floats(domain), integral)  # an integer for a float parameter too
    elif kind == "pair":
        element = floats(domain["element"])
        base = st.lists(element, min_size=2, max_size=2, unique=True).map(
            lambda v: tuple(sorted(v))
        )
    else:
        raise AssertionError(f"a domain this test does not know: {domain}")
    return st.one_of(st.just(domain["or"]), base) if "or" in domain else base


@st.composite
def configs(draw: st.DrawFn, method: str) -> ExtractionConfig:
    info = method_info(method)
    names = draw(st.lists(st.sampled_from(sorted(info.params)), unique=True))
    params = {name: draw(values(info.params[name].domain)) for name in names}
    preset = draw(st.sampled_from([None, *info.presets]))
    return ExtractionConfig(method, preset, params)


def typed(config: ExtractionConfig) -> tuple:
    """The configuration with the type of every value (and of a pair's elements)."""

    def kinds(value):
        return (type(value), *map(type, value)) if isinstance(value, tuple) else type(value)

    return config, {name: kinds(value) for name, value in config.params.items()}


# ----------------------------------------------------------------------- round trips


@pytest.mark.parametrize("method", METHODS)
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_every_spelling_gives_the_configuration_back(method, data, tmp_path_factory) -> None:
    config = data.draw(configs(method))
    path = tmp_path_factory.mktemp("config") / "c.toml"
    path.write_text(config.to_toml(), encoding="utf-8")
    assert typed(load_config(path)) == typed(config)

    as_json = json.loads(json.dumps(config.to_dict()))
    assert typed(ExtractionConfig.from_dict(as_json)) == typed(config)

    words = shlex.split(config.command("some log.clf"))
    assert words[:3] == ["scanlines", "run", "some log.clf"]
    assert words[words.index("--method") + 1] == config.method
    assert ("--preset" in words) == (config.preset is not None)
    given_params = [words[k + 1] for k, word in enumerate(words) if word == "--param"]
    method_, preset, params = method_options(
        words[words.index("--method") + 1],
        words[words.index("--preset") + 1] if "--preset" in words else None,
        given_params,
        None,
    )
    assert typed(ExtractionConfig(method_, preset, params)) == typed(config)
    # the resolved parameters are those of the extractor the overrides make
    assert config.resolved() == dict(Extractor(method, config.preset, **config.params).params)


def test_each_kind_of_value_has_its_spelling() -> None:
    config = ExtractionConfig(
        "adaptive",
        "paper",
        {"min_points": "6", "k": 2, "fit": "tls", "merge": "true", "range_sigma": "AUTO"}
        | {"max_residual": "off", "dkth_range": "0,0.05", "dkth_step": 1e-9},
    )
    assert list(config.params.items()) == [
        ("k", 2.0),
        ("dkth_range", (0.0, 0.05)),
        ("dkth_step", 1e-9),
        ("fit", "tls"),
        ("merge", True),
        ("max_residual", None),
        ("min_points", 6),
        ("range_sigma", "auto"),
    ]  # checked, typed, in the method's order (clustering, segments, output)
    text = config.to_toml()
    assert text.splitlines()[:6] == [
        "# scanlines extraction configuration",
        'method = "adaptive"',
        'preset = "paper"',
        "",
        "[params]",
        "k = 2.0",
    ]
    for line in (
        'range_sigma = "auto"',
        "k = 2.0",
        "dkth_range = [",  # one number a line
        "dkth_step = 1e-09",
        'fit = "tls"',
        "merge = true",
        'max_residual = "none"',
    ):
        assert line in text.splitlines()
    assert config.cli_values() == {
        "min_points": "6",
        "range_sigma": "auto",
        "k": "2.0",
        "dkth_range": "0.0,0.05",
        "dkth_step": "1e-09",
        "fit": "tls",
        "merge": "true",
        "max_residual": "none",
    }
    assert config.to_dict()["params"]["dkth_range"] == [0.0, 0.05]
    assert config.to_dict()["params"]["max_residual"] is None
    assert tomllib.loads(text)["params"]["dkth_step"] == 1e-9
    assert tomllib.loads(text)["params"]["dkth_range"] == [0.0, 0.05]


def test_a_configuration_is_a_value() -> None:
    import pickle

    config = ExtractionConfig("iepf", params={"min_points": 4})
    assert config == ExtractionConfig("iepf", None, {"min_points": "4"})
    assert hash(config) == hash(ExtractionConfig("iepf", None, {"min_points": 4.0}))
    assert pickle.loads(pickle.dumps(config)) == config
    assert repr(config) == "ExtractionConfig(method='iepf', preset=None, params={'min_points': 4})"
    with pytest.raises(TypeError):
        config.params["min_points"] = 5  # type: ignore[index]
    assert ExtractionConfig().to_toml() == (
        '# scanlines extraction configuration\nmethod = "adaptive"\n\n[params]\n'
    )
    assert ExtractionConfig().command() == "scanlines run LOG --method adaptive"


def test_a_config_file_that_sets_nothing_is_the_default(tmp_path) -> None:
    path = tmp_path / "empty.toml"
    path.write_text("# nothing\n")
    assert load_config(path) == ExtractionConfig()
    assert ExtractionConfig.from_dict({}) == ExtractionConfig()
    assert ExtractionConfig.from_dict({"method": "iepf", "preset": None, "params": None}) == (
        ExtractionConfig("iepf")
    )


# ---------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    ("text", "needles"),
    [
        ('method = "adaptive"\n[params]\nk = \n', ["line 3", "not valid TOML", "column 5"]),
        ('methd = "adaptive"\n', ["line 1", "key methd", "unknown key", "method, preset, params"]),
        ("method = 3\n", ["key method", "string"]),
        ('method = "nope"\n', ["key method", "unknown method 'nope'", "iepf"]),
        ('method = "iepf"\npreset = "paper"\n', ["line 2", "key preset", "unknown preset"]),
        ('method = "iepf"\n\n[params]\nfoo = 1\n', ["line 4", "key params.foo", "unknown param"]),
        ('[params]\nmin_points = "6"\n', ["line 2", "key params.min_points", "without quotes"]),
        ('[params]\nmerge = "yes"\n', ["key params.merge", "true or false"]),
        ('[params]\ndkth_range = "0,1"\n', ["key params.dkth_range", "[a, b]"]),
        ("[params]\ndkth_range = [1.0, 0.5]\n", ["key params.dkth_range", "a < b"]),
        ("[params]\nk = -1\n", ["line 2", "key params.k", "k must be a number in (0"]),
        ("params = 3\n", ["line 1", "key params", "table"]),
    ],
)
def test_a_bad_file_is_one_line_naming_it(tmp_path, text, needles) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    message = str(caught.value)
    assert isinstance(caught.value, ParameterError)
    assert message.startswith(f"{path}")
    assert "\n" not in message
    for needle in needles:
        assert needle in message, message


def test_unreadable_files_are_one_line_naming_them(tmp_path) -> None:
    for path, needle in (
        (tmp_path / "missing.toml", "no such file or directory"),
        (tmp_path, "directory"),
    ):
        with pytest.raises(ConfigError, match=needle) as caught:
            load_config(path)
        assert str(caught.value).startswith(str(path))
    binary = tmp_path / "log.toml"
    binary.write_bytes(b"\x1f\x8b\x08\x00\xff\xfe")
    with pytest.raises(ConfigError, match="not UTF-8"):
        load_config(binary)


def test_a_bad_dict_names_its_source() -> None:
    with pytest.raises(ConfigError, match=r"^request, key params\.k: k must be a number"):
        ExtractionConfig.from_dict({"params": {"k": "3"}}, source="request")
    with pytest.raises(ConfigError, match=r"^request, key colour: unknown key"):
        ExtractionConfig.from_dict({"colour": 1}, source="request")
    with pytest.raises(ConfigError, match="a configuration is a table"):
        ExtractionConfig.from_dict([1, 2])
    # the Python API takes what Extractor takes, strings included, and names the key
    with pytest.raises(ConfigError, match=r"^key params\.k: k must be"):
        ExtractionConfig(params={"k": "x"})


# ------------------------------------------------------------------ command options


@pytest.fixture
def tuned(tmp_path) -> Path:
    path = tmp_path / "tuned.toml"
    config = ExtractionConfig("adaptive", "paper", {"k": 2.5, "min_points": 6})
    path.write_text(config.to_toml())
    return path


def test_command_line_options_override_the_file(tuned) -> None:
    assert method_options(None, None, None, tuned) == (
        "adaptive",
        "paper",
        {"k": 2.5, "min_points": 6},
    )
    assert method_options("adaptive", None, ["k=4"], tuned) == (
        "adaptive",
        "paper",
        {"k": "4", "min_points": 6},
    )
    untuned = tuned.with_name("untuned.toml")
    untuned.write_text('method = "adaptive"\n\n[params]\nk = 2.5\n')
    assert method_options(None, "paper", ["window=5"], untuned) == (
        "adaptive",
        "paper",
        {"k": 2.5, "window": "5"},
    )
    assert method_options(None, None, None, None) == ("adaptive", None, {})
    assert method_options("iepf", None, ["k=2"], None) == ("iepf", None, {"k": "2"})


def test_another_method_than_the_files_is_an_error_when_the_file_sets_its_parameters(
    tuned, tmp_path
) -> None:
    with pytest.raises(ParameterError) as caught:
        method_options("iepf", None, None, tuned)
    message = str(caught.value)
    for needle in ("--method iepf", "'adaptive'", "tuned.toml", "preset 'paper'", "k, min_points"):
        assert needle in message, message
    bare = tmp_path / "bare.toml"
    bare.write_text('method = "adaptive"\n')
    assert method_options("iepf", None, ["k=2"], bare) == ("iepf", None, {"k": "2"})
    preset_only = tmp_path / "preset.toml"
    preset_only.write_text('method = "adaptive"\npreset = "paper"\n')
    with pytest.raises(ParameterError, match="preset 'paper'"):
        method_options("iepf", None, None, preset_only)


# ------------------------------------------------------------------------ the CLI


def records(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_run_with_the_file_equals_run_with_its_command(tmp_path) -> None:
    config = ExtractionConfig(
        "adaptive", None, {"min_points": 6, "dkth_range": (0.0, 0.05), "max_residual": None}
    )
    (tmp_path / "c.toml").write_text(config.to_toml())
    log = sample("intel")
    by_file = cli(
        "run", log, "--scans", "0:3", "--config", "c.toml", "--out", "a.jsonl", cwd=tmp_path
    )
    assert by_file.returncode == 0, by_file.stderr
    words = shlex.split(config.command(str(log)))
    assert words[:2] == ["scanlines", "run"]
    by_line = cli(*words[1:], "--scans", "0:3", "--out", "b.jsonl", cwd=tmp_path)
    assert by_line.returncode == 0, by_line.stderr
    a, b = records(tmp_path / "a.jsonl"), records(tmp_path / "b.jsonl")
    assert [r["scan"] for r in a] == [0, 1, 2]
    assert [r["segments"] for r in a] == [r["segments"] for r in b]
    assert all(len(s["segments"]) > 0 for s in a)
    meta_a = json.loads((tmp_path / "a.jsonl.meta.json").read_text())
    meta_b = json.loads((tmp_path / "b.jsonl.meta.json").read_text())
    assert meta_a["params"] == meta_b["params"]
    assert meta_a["params"]["min_points"] == 6
    assert meta_a["params"]["dkth_range"] == [0.0, 0.05]
    assert meta_a["params"]["max_residual"] is None


def test_run_param_overrides_the_file(tuned, tmp_path) -> None:
    out = cli(
        "run", sample("intel"), "--scans", "0:2", "--config", tuned, "--param", "k=4",
        "--out", tmp_path / "o.jsonl",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    meta = json.loads((tmp_path / "o.jsonl.meta.json").read_text())
    assert meta["params"]["k"] == 4.0  # the command line's
    assert meta["params"]["min_points"] == 6  # the file's
    assert meta["params"]["fit"] == "paper"  # the file's preset's


@pytest.mark.parametrize(
    ("text", "args", "needles"),
    [
        (None, [], ["conf.toml", "no such file or directory"]),
        ('method = "adaptive"\n[params\n', [], ["conf.toml, line 2", "not valid TOML"]),
        ('method = "adaptive"\nparam = 1\n', [], ["conf.toml, line 2", "key param"]),
        ("[params]\nk = true\n", [], ["conf.toml", "key params.k", "got True"]),
        ('method = "sonar"\n', [], ["conf.toml", "unknown method 'sonar'"]),
        ("[params]\nkk = 1\n", [], ["conf.toml", "key params.kk", "unknown parameter"]),
        ("[params]\nwindow = 0\n", [], ["conf.toml", "window must be an integer in [1, 1000]"]),
        ("[params]\nk = 2\n", ["--method", "iepf"], ["conf.toml", "--method iepf", "'adaptive'"]),
        ("[params]\nk = 2\n", ["--param", "k=x"], ["k must be a number"]),
    ],
)
def test_run_with_a_bad_config_exits_2_with_one_line(tmp_path, text, args, needles) -> None:
    if text is not None:
        (tmp_path / "conf.toml").write_text(text)
    out = cli("run", sample("intel"), "--config", "conf.toml", *args, cwd=tmp_path)
    one_error_line(out, *needles)


@pytest.fixture(scope="module")
def room_npz(tmp_path_factory) -> Path:
    scan = scan_of(square_room(), fov_deg=340, step_deg=1 / 3, sigma=0.01, seed=0, start_deg=-170)
    path = tmp_path_factory.mktemp("room") / "room.npz"
    np.savez(
        path, ranges=scan.ranges, angle_min=scan.angle_min, angle_increment=scan.angle_increment
    )
    return path


def test_extract_takes_a_config(room_npz, tmp_path) -> None:
    config = ExtractionConfig("iepf", None, {"min_points": 8, "split_distance": 0.05})
    path = tmp_path / "iepf.toml"
    path.write_text(config.to_toml())
    by_file = cli("extract", room_npz, "--json", "--config", path)
    assert by_file.returncode == 0, by_file.stderr
    words = shlex.split(config.command(str(room_npz)))
    by_line = cli("extract", *words[2:], "--json")
    assert by_line.returncode == 0, by_line.stderr
    a, b = json.loads(by_file.stdout), json.loads(by_line.stdout)
    assert a == b
    assert a["method"] == "iepf"
    assert a["params"]["min_points"] == 8
    bad = tmp_path / "bad.toml"
    bad.write_text('preset = "fast"\n')
    one_error_line(cli("extract", room_npz, "--config", bad), "bad.toml", "key preset")


def test_eval_takes_configs_as_method_rows(tmp_path) -> None:
    config = ExtractionConfig("adaptive", None, {"min_points": 6, "dkth_range": (0.0, 0.05)})
    (tmp_path / "tuned.toml").write_text(config.to_toml())
    args = [
        "eval",
        "sim",
        "-s",
        "lms_1deg",
        "-n",
        "1",
        "--no-plots",
        "-j",
        "1",
        "--config",
        "tuned.toml",
    ]
    only = cli(*args, "--out", "only", cwd=tmp_path)
    assert only.returncode == 0, only.stderr
    summary = json.loads((tmp_path / "only" / "summary.json").read_text())
    (spec,) = summary["config"]["specs"]
    assert spec["label"] == "tuned.toml"
    assert spec["spec"] == "adaptive?dkth_range=0.0,0.05&min_points=6"
    both = cli(*args, "-m", "adaptive", "--out", "both", cwd=tmp_path)
    assert both.returncode == 0, both.stderr
    with (tmp_path / "both" / "summary.csv").open(newline="") as handle:
        labels = {row["label"] for row in csv.DictReader(handle)}
    assert labels == {"adaptive", "tuned.toml"}
    (tmp_path / "bad.toml").write_text("[params]\nk = 0\n")
    one_error_line(
        cli("eval", "sim", "--config", "bad.toml", "--out", "x", cwd=tmp_path), "bad.toml"
    )
