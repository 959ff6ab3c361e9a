"""``scanlines.evaluation`` and ``scanlines eval``: specs, seeds, scene sets, outputs."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import Ran, scanlines
from scanlines.errors import LogFormatError, ParameterError
from scanlines.evaluation.evaluate import ALL_SENSORS, evaluate, event_f1, worst_scans
from scanlines.evaluation.scenes import (
    generate_scene_set,
    load_scene_set,
    make_scene,
    scene_seed,
)
from scanlines.evaluation.scores import Tolerances
from scanlines.evaluation.specs import MethodSpec, parse_spec, parse_specs

SPECS = ("adaptive", "adaptive:paper")
SENSORS = ("lms_1deg", "urg04lx")


def run(*args: str, cwd: Path | None = None) -> Ran:
    return scanlines(*args, cwd=cwd)


def scores_of(result) -> list[dict]:
    """Per-scan rows without the timing, which differs between runs."""
    return [{k: v for k, v in row.items() if k != "us"} for row in result.per_scan_rows()]


def same_rows(a: list[dict], b: list[dict]) -> bool:
    def norm(v):
        return "nan" if isinstance(v, float) and math.isnan(v) else v

    return [{k: norm(v) for k, v in r.items()} for r in a] == [
        {k: norm(v) for k, v in r.items()} for r in b
    ]


@pytest.fixture(scope="module")
def small_result():
    return evaluate(SPECS, SENSORS, 3, seed=5)


# --------------------------------------------------------------------------- specs


@pytest.mark.parametrize(
    ("text", "method", "preset", "params", "label"),
    [
        ("adaptive", "adaptive", None, (), "adaptive"),
        ("adaptive:paper", "adaptive", "paper", (), "adaptive:paper"),
        ("adaptive?k=4&fit=paper", "adaptive", None, (("k", "4"), ("fit", "paper")), None),
        (" adaptive:paper?k=4@paper k4 ", "adaptive", "paper", (("k", "4"),), "paper k4"),
        ("adaptive?dkth_range=0,0.05", "adaptive", None, (("dkth_range", "0,0.05"),), None),
    ],
)
def test_parse_good_specs(text, method, preset, params, label):
    spec = parse_spec(text)
    assert (spec.method, spec.preset, spec.params) == (method, preset, params)
    assert spec.label == (label or text.strip())
    assert parse_spec(spec.text) == MethodSpec(method, preset, params)
    spec.extractor()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "no method name"),
        ("nope", "unknown method 'nope'"),
        ("adaptive:nope", "unknown preset 'nope'"),
        ("adaptive:", "empty preset"),
        ("adaptive?", "no NAME=VALUE"),
        ("adaptive?k", "NAME=VALUE"),
        ("adaptive?k=", "NAME=VALUE"),
        ("adaptive?zz=1", "unknown parameter(s) zz"),
        ("adaptive?k=abc", "k must be a number"),
        ("adaptive?k=3&k=4", "given twice: k"),
        ("adaptive@", "empty label"),
    ],
)
def test_parse_bad_specs(text, message):
    with pytest.raises(ParameterError, match="method spec") as info:
        parse_spec(text)
    assert message in str(info.value)


def test_specs_need_distinct_labels():
    specs = parse_specs(["adaptive", "adaptive?k=4", "adaptive@again"])
    assert [s.label for s in specs] == ["adaptive", "adaptive?k=4", "again"]
    with pytest.raises(ParameterError, match="used twice: adaptive"):
        parse_specs(["adaptive", "adaptive:paper@adaptive"])
    with pytest.raises(ParameterError, match="at least one"):
        parse_specs([])
    with pytest.raises(ParameterError, match="unknown preset"):
        parse_specs([MethodSpec("adaptive", "nope")])


# --------------------------------------------------------------------------- seeds, runs


def test_scene_seeds_are_fixed_and_distinct():
    seeds = {scene_seed(0, s, i) for s in ("lms_1deg", "tim571") for i in range(50)}
    assert len(seeds) == 100
    assert scene_seed(0, "tim571", 3) == scene_seed(0, "tim571", 3)
    assert scene_seed(0, "tim571", 3) != scene_seed(1, "tim571", 3)
    assert all(0 <= s < 2**32 for s in seeds)


def test_same_seed_same_results(small_result):
    again = evaluate(SPECS, SENSORS, 3, seed=5)
    assert same_rows(scores_of(small_result), scores_of(again))
    other = evaluate(SPECS, SENSORS, 3, seed=6)
    assert [r.seed for r in other.records] != [r.seed for r in small_result.records]


def test_every_spec_sees_the_same_scans(small_result):
    rows = small_result.per_scan_rows()
    assert len(rows) == len(SENSORS) * 3 * len(SPECS)
    by_scan: dict[tuple, set] = {}
    for row in rows:
        by_scan.setdefault((row["sensor"], row["scene"]), set()).add((row["seed"], row["label"]))
    assert len(by_scan) == len(SENSORS) * 3
    for entries in by_scan.values():
        assert len({seed for seed, _ in entries}) == 1
        assert {label for _, label in entries} == set(SPECS)


def test_summaries_pool_the_scans(small_result):
    groups = [*SENSORS, ALL_SENSORS]
    assert [(r.sensor, r.spec.label) for r in small_result.summaries] == [
        (s, label) for s in groups for label in SPECS
    ]
    for label in SPECS:
        per_sensor = [small_result.summary(s, label).summary for s in SENSORS]
        pooled = small_result.summary(ALL_SENSORS, label).summary
        assert pooled.n_scans == sum(s.n_scans for s in per_sensor) == 6
        assert pooled.breakpoints.tp == sum(s.breakpoints.tp for s in per_sensor)
        assert small_result.summary(ALL_SENSORS, label).median_us > 0


def test_workers_give_the_same_scores(small_result):
    parallel = evaluate(SPECS, SENSORS, 3, seed=5, workers=2)
    assert same_rows(scores_of(small_result), scores_of(parallel))


def test_adaptive_on_exact_scans_meets_a_floor():
    # measured (10 scenes, seed 0): breakpoint F1 0.94, TruePos 0.99
    result = evaluate(["adaptive"], ["lms_1deg"], 10, seed=0, noise="exact")
    pooled = result.summary("lms_1deg", "adaptive").summary
    assert pooled.breakpoints.f1 > 0.8
    assert pooled.segments.true_pos > 0.85
    assert pooled.similarity.mean < 0.01


def test_bad_arguments_raise_parameter_errors():
    with pytest.raises(ParameterError, match="unknown sensor preset 'nope'"):
        evaluate(["adaptive"], ["nope"], 1)
    with pytest.raises(ParameterError, match="noise must be one of"):
        evaluate(["adaptive"], ["lms_1deg"], 1, noise="loud")
    with pytest.raises(ParameterError, match="scenes per sensor"):
        evaluate(["adaptive"], ["lms_1deg"], 0)
    with pytest.raises(ParameterError, match="seed"):
        evaluate(["adaptive"], ["lms_1deg"], 1, seed=-1)
    with pytest.raises(ParameterError, match="workers"):
        evaluate(["adaptive"], ["lms_1deg"], 1, workers=0)


def test_worst_scans_rank_by_event_f1(small_result):
    worst = worst_scans(small_result, 3)
    assert len(worst) == 3
    assert [w.score for w in worst] == sorted(w.score for w in worst)
    everything = worst_scans(small_result, 100)
    assert len(everything) == 6
    assert worst[0].score == min(w.score for w in everything)
    for w in worst:
        f1 = [event_f1(r.score) for r in small_result.records if r.seed == w.seed]
        assert w.score == pytest.approx(np.mean(f1))
        assert [label for label, _ in w.f1_by_label] == list(SPECS)


def test_json_states_the_tolerances_and_has_no_nan(small_result, tmp_path):
    path = small_result.to_json(tmp_path / "s.json", per_scan=True)
    data = json.loads(path.read_text(), parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
    assert data["tolerances"]["event_beams"] == Tolerances().event_beams
    assert data["tolerances"]["alpha_deg"] == pytest.approx(4.0)
    assert data["config"]["tolerances"] == data["tolerances"]
    assert [s["label"] for s in data["config"]["specs"]] == list(SPECS)
    assert data["config"]["specs"][1]["resolved"]["fit"] == "paper"
    assert len(data["summary"]) == 6
    assert len(data["per_scan"]) == 12


# --------------------------------------------------------------------------- scene sets


def test_saved_scene_set_round_trips(tmp_path):
    path = generate_scene_set(["tim571", "lms_1deg"], 2, seed=3).save(tmp_path / "set.npz")
    loaded = load_scene_set(path)
    assert loaded.sensors == ("tim571", "lms_1deg")
    assert (loaded.seed, loaded.noise, len(loaded)) == (3, "realistic", 4)
    original = make_scene("lms_1deg", 1, 3)
    copy = loaded.find("lms_1deg", 1)
    assert (copy.seed, copy.kind) == (original.seed, original.kind)
    np.testing.assert_array_equal(copy.scan.ranges, original.scan.ranges)
    assert copy.scan.pose == original.scan.pose
    for name in ("breakpoints", "corners", "corner_points", "hit_points", "status", "on_curve"):
        np.testing.assert_array_equal(getattr(copy.truth, name), getattr(original.truth, name))
    np.testing.assert_array_equal(copy.truth.segments.rho, original.truth.segments.rho)

    generated = evaluate(SPECS, ["tim571", "lms_1deg"], 2, seed=3)
    from_file = evaluate(SPECS, scenes=loaded)
    assert same_rows(scores_of(generated), scores_of(from_file))
    assert from_file.config.source == str(path)
    in_workers = evaluate(SPECS, scenes=loaded, workers=2)
    assert same_rows(scores_of(generated), scores_of(in_workers))


def test_scene_set_selection(tmp_path):
    scenes = generate_scene_set(["lms_1deg", "urg04lx"], 3, seed=1, noise="exact")
    picked = scenes.select(["urg04lx"], 2)
    assert [(c.sensor, c.index) for c in picked.cases] == [("urg04lx", 0), ("urg04lx", 1)]
    result = evaluate(["adaptive"], ["urg04lx"], 2, scenes=scenes)
    assert result.config.noise == "exact"
    assert len(result.records) == 2
    with pytest.raises(ParameterError, match="no scenes of tim571"):
        scenes.select(["tim571"])


def test_not_a_scene_set(tmp_path):
    bad = tmp_path / "bad.npz"
    np.savez(bad, ranges=np.ones(3))
    with pytest.raises(LogFormatError, match=r"bad\.npz"):
        load_scene_set(bad)
    text = tmp_path / "text.npz"
    text.write_text("hello")
    with pytest.raises(LogFormatError, match="not a scene set"):
        load_scene_set(text)


# --------------------------------------------------------------------------- command


def test_import_needs_neither_matplotlib_nor_rich():
    code = (
        "import sys, scanlines.evaluation.evaluate, scanlines.viz.evaluation; "
        "print([m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'rich')])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


@pytest.fixture(scope="module")
def eval_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("eval")
    args = ["eval", "sim", "-m", "adaptive", "-m", "adaptive:paper", "--seed", "2"]
    args += ["-s", "lms_1deg", "-s", "tim571", "-n", "3", "--tol-beams", "3"]
    out = run(*args, "--out", str(folder / "out"), "--save-scenes", str(folder / "set.npz"))
    return folder, out


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def test_eval_command_writes_everything(eval_run):
    folder, out = eval_run
    assert out.returncode == 0, out.stderr
    names = ("per_scan.csv", "summary.csv", "summary.json", "bars.png", "worst.png")
    for name in names:
        path = folder / "out" / name
        assert path.stat().st_size > 0
        assert str(path) in out.stdout
    assert (folder / "set.npz").exists()
    assert "tolerances: events +-3 beams" in out.stdout
    for title in ("lms_1deg: 3 scans", "tim571: 3 scans", "all: 6 scans"):
        assert title in out.stdout

    per_scan = read_csv(folder / "out" / "per_scan.csv")
    assert len(per_scan) == 2 * 3 * 2
    expected = {"sensor", "scene", "seed", "label", "us", "bp_f1", "corner_f1"}
    expected |= {"seg_true_pos", "seg_false_pos", "sim_mean", "accuracy_rate"}
    expected |= {f"tol_{name}" for name in Tolerances().to_dict()}
    assert expected <= set(per_scan[0])
    assert {row["tol_event_beams"] for row in per_scan} == {"3"}
    assert {row["label"] for row in per_scan} == {"adaptive", "adaptive:paper"}

    summary = read_csv(folder / "out" / "summary.csv")
    assert len(summary) == 3 * 2
    assert {"median_us", "n_scans", "tol_rho", "accuracy_rate_pooled"} <= set(summary[0])
    assert [row["sensor"] for row in summary] == ["lms_1deg"] * 2 + ["tim571"] * 2 + ["all"] * 2

    data = json.loads((folder / "out" / "summary.json").read_text())
    assert data["tolerances"]["event_beams"] == 3
    assert data["config"]["seed"] == 2


def test_eval_command_on_saved_scenes(eval_run, tmp_path):
    folder, first = eval_run
    assert first.returncode == 0, first.stderr
    args = [
        "eval",
        "sim",
        "-m",
        "adaptive",
        "-m",
        "adaptive:paper",
        "--tol-beams",
        "3",
        "--no-plots",
    ]
    out = run(*args, "--scenes", str(folder / "set.npz"), "--out", str(tmp_path))
    assert out.returncode == 0, out.stderr
    assert not (tmp_path / "worst.png").exists()

    def scores(path: Path) -> list[dict[str, str]]:
        return [{k: v for k, v in r.items() if k != "us"} for r in read_csv(path)]

    assert scores(tmp_path / "per_scan.csv") == scores(folder / "out" / "per_scan.csv")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-m", "adaptive?k=abc"], "k must be a number"),
        (["-m", "nope"], "unknown method 'nope'"),
        (["-s", "nope"], "unknown sensor preset 'nope'"),
        (["--noise", "loud"], "noise must be one of"),
        (["--tol-beams", "-1"], "bad tolerance"),
        (["-n", "0"], "scenes per sensor must be an integer >= 1"),
        (["--scenes", "there.npz", "--seed", "1"], "--seed and --noise"),
        (["--scenes", "missing.npz"], "missing.npz"),
    ],
)
def test_eval_command_bad_input_exits_2(args, message, tmp_path):
    (tmp_path / "there.npz").write_bytes(b"")  # there: the option check speaks first
    out = run("eval", "sim", "-n", "1", "--out", str(tmp_path), *args, cwd=tmp_path)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("scanlines: error:")
    assert message in lines[0]
