"""``scanlines eval`` as subcommands (sim, family, labels, real, map, trajectory), and its
old flag forms still running, each with one line naming the new form."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

from cli_helpers import scanlines
from scanlines.cli.eval_legacy import subcommand_args
from scanlines.data import sample
from scanlines.map.poses import write_tum

SUBCOMMANDS = ["sim", "family", "labels", "real", "map", "trajectory"]
NOTE = re.compile(r"^scanlines: note: this is now `scanlines eval (.+)`$")


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ([], ["sim"]),
        (["-m", "X", "-n", "60", "--seed", "0"], ["sim", "-m", "X", "-n", "60", "--seed", "0"]),
        (["--real", "a.log", "--scans", "9"], ["real", "a.log", "--scans", "9"]),
        (["--scans", "9", "--real", "a", "--real=b"], ["real", "a", "b", "--scans", "9"]),
        (["--labels", "urg", "-m", "iepf"], ["labels", "urg", "-m", "iepf"]),
        (["--labels", "intel", "--labels", "urg"], ["labels", "intel", "urg"]),
        (["--map", "m.log", "--align"], ["map", "m.log", "--align"]),
        (
            ["--trajectory", "e.tum", "--reference", "r"],
            ["trajectory", "e.tum", "--reference", "r"],
        ),
        (
            ["--family", "-n", "2", "--family-count", "2"],
            ["family", "-n", "2", "--family-count", "2"],
        ),
    ],
)
def test_the_old_forms_are_read_as_subcommands(old, new):
    assert subcommand_args(old) == (new, bool(old))


@pytest.mark.parametrize("args", [["real", "a.log"], ["--help"], ["map", "--help"]])
def test_subcommand_forms_are_left_as_they_are(args):
    assert subcommand_args(args) == (args, False)


def test_two_kinds_of_evaluation_at_once_is_one_line():
    ran = scanlines("eval", "--real", "a.log", "--map", "b.log")
    assert ran.returncode == 2
    assert ran.stderr.strip().splitlines() == [
        "scanlines: error: --real, --map: one kind of evaluation at a time (scanlines eval --help)"
    ]


def test_eval_help_names_every_subcommand():
    ran = scanlines("eval", "--help", columns=200)
    assert ran.returncode == 0, ran.stderr
    for name in SUBCOMMANDS:
        assert re.search(rf"^\W*{name}\s+\w", ran.stdout, re.MULTILINE), (name, ran.stdout)


@pytest.mark.parametrize("name", SUBCOMMANDS)
def test_each_subcommand_has_its_own_help(name):
    ran = scanlines("eval", name, "--help", columns=200)
    assert ran.returncode == 0, ran.stderr
    assert f"Usage: scanlines eval {name}" in ran.stdout
    assert "--out" in ran.stdout


def _note(stderr: str) -> str:
    """The one note line naming the new form (there must be exactly one)."""
    notes = [NOTE.match(line) for line in stderr.splitlines()]
    found = [m.group(1) for m in notes if m]
    assert len(found) == 1, stderr
    return found[0]


def _same_run(old: list, new: list, tmp_path: Path, files: list[str]) -> None:
    """``eval OLD`` and ``eval NEW`` write the same files (the old one names the new form)."""
    ran_old = scanlines("eval", *old, "--out", tmp_path / "old", cwd=tmp_path)
    assert ran_old.returncode == 0, ran_old.stderr
    ran_new = scanlines("eval", *new, "--out", tmp_path / "new", cwd=tmp_path)
    assert ran_new.returncode == 0, ran_new.stderr
    assert not NOTE.search(ran_new.stderr)
    assert _note(ran_old.stderr).startswith(" ".join(str(a) for a in new[:1]))
    for name in files:
        assert (tmp_path / "old" / name).exists(), name
        assert (tmp_path / "new" / name).exists(), name
    return ran_old, ran_new


def test_eval_sim_and_the_plain_old_form(tmp_path):
    args = ["-m", "iepf", "-s", "lms_1deg", "-n", "2", "--seed", "0", "--no-plots", "-j", "1"]
    old, new = _same_run(args, ["sim", *args], tmp_path, ["summary.csv"])
    assert _note(old.stderr) == f"sim {' '.join(args)} --out {tmp_path / 'old'}"
    assert (tmp_path / "old" / "summary.csv").read_text().splitlines()[0] == (
        tmp_path / "new" / "summary.csv"
    ).read_text().splitlines()[0]
    assert "count rate" in new.stdout
    assert "accuracy rate" in new.stdout
    assert "mean per-scan rate" not in new.stdout


def test_eval_family_and_its_old_form(tmp_path):
    args = ["-n", "1", "--family-count", "1", "-m", "iepf", "--no-plots", "-j", "1"]
    _same_run(["--family", *args], ["family", *args], tmp_path, ["family.csv"])
    rows = list(csv.DictReader((tmp_path / "new" / "family.csv").open()))
    assert {r["label"] for r in rows} == {"iepf", "truth"}


def test_eval_labels_and_its_old_form(tmp_path):
    _same_run(["--labels", "urg", "-m", "iepf"], ["labels", "urg", "-m", "iepf"], tmp_path,
              ["labelled.csv"])  # fmt: skip
    rows = list(csv.DictReader((tmp_path / "new" / "labelled.csv").open()))
    assert [(r["sample"], r["method"]) for r in rows] == [("urg", "iepf")]


def test_eval_real_and_its_old_form(tmp_path):
    log = str(sample("intel"))
    args = ["--scans", "20", "--pairs", "3", "-m", "iepf"]
    _same_run(["--real", log, *args], ["real", log, *args], tmp_path, ["repeatability.csv"])
    old = (tmp_path / "old" / "repeatability.csv").read_text()
    assert old == (tmp_path / "new" / "repeatability.csv").read_text()


def test_eval_map_and_its_old_form(tmp_path):
    log = str(sample("intel"))
    _same_run(["--map", log, "--scans", "60"], ["map", log, "--scans", "60"], tmp_path,
              ["map_eval.json"])  # fmt: skip
    old, new = (json.loads((tmp_path / d / "map_eval.json").read_text()) for d in ("old", "new"))
    assert old["lines"] == new["lines"]
    assert old["coverage"] == new["coverage"]


def test_eval_map_scores_one_method(tmp_path):
    ran = scanlines("eval", "map", sample("intel"), "-m", "iepf", "-m", "adaptive", cwd=tmp_path)
    assert ran.returncode == 2
    assert ran.stderr.strip().splitlines() == [
        "scanlines: error: eval map scores one method: give one --method or one --config"
    ]


def test_eval_trajectory_and_its_old_form(tmp_path):
    from scanlines.io import open_log

    with open_log(sample("intel")) as reader:
        scans = [s for _, s in zip(range(30), reader, strict=False)]
    write_tum(tmp_path / "est.tum", [(s.timestamp, s.pose) for s in scans])
    est, ref = tmp_path / "est.tum", sample("intel")
    _same_run(["--trajectory", est, "--reference", ref], ["trajectory", est, "--reference", ref],
              tmp_path, ["trajectory_eval.json"])  # fmt: skip
    score = json.loads((tmp_path / "new" / "trajectory_eval.json").read_text())
    assert score["matched"] == 30
