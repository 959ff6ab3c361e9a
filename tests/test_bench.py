"""``scanlines bench`` and ``python -m tools.bench``: JSON layout, the generated page, errors.
Speed itself is never asserted."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import scanlines
from scanlines.bench import measure
from scanlines.bench.results import SCHEMA
from scanlines.methods import REGISTRY
from scanlines.methods.iepf import Iepf
from scanlines.report import microseconds
from tools.bench.performance_page import render_markdown

pytestmark = pytest.mark.slow  # timing runs

REPOSITORY = Path(__file__).parents[1]


def run(*args: str, page: Path | None = None) -> subprocess.CompletedProcess:
    """``scanlines bench ARGS``; with ``page``, the repository's page writer instead."""
    command = ["scanlines", "bench"] if page is None else ["tools.bench", "--out", str(page)]
    return subprocess.run(
        [sys.executable, "-m", *command, *args],
        cwd=REPOSITORY,
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """One quick run of every method, writing both the JSON and the docs page."""
    folder = tmp_path_factory.mktemp("bench")
    out = run(
        "--quick",
        "--json",
        str(folder / "out.json"),
        page=folder / "PERFORMANCE.md",
    )
    return out, folder


def test_quick_json_has_every_method_and_positive_timings(quick_run):
    out, folder = quick_run
    assert out.returncode == 0, out.stderr
    data = json.loads((folder / "out.json").read_text())
    assert data["schema"] == SCHEMA
    selected = list(scanlines.method_names())
    assert data["methods"] == selected
    assert data["settings"]["quick"] is True
    assert data["reference"]["method"] == "iepf"
    names = [d["name"] for d in data["datasets"]]
    assert names[:2] == ["intel", "freiburg"]
    assert len(names) == 2 + 4  # the real excerpts and the four sensor presets
    for dataset in data["datasets"]:
        results = dataset["results"]
        assert list(results) == selected
        for timing in results.values():
            assert timing["status"] == "ok", timing["error"]
            assert timing["median_us"] > 0
            assert timing["p90_us"] >= timing["median_us"] - 1e-9
            assert timing["scans_per_s"] > 0
            assert timing["samples"] == dataset["n_scans"]  # quick: one repeat
        assert results["iepf"]["ratio"] == 1.0
    assert data["machine"]["cpu"]
    assert data["machine"]["numpy"]


def test_quick_scaling_entries(quick_run):
    out, folder = quick_run
    assert out.returncode == 0, out.stderr
    scaling = json.loads((folder / "out.json").read_text())["scaling"]
    assert [e["n_beams"] for e in scaling["entries"]] == [100, 1000]
    for entry in scaling["entries"]:
        assert set(entry["results"]) == set(scanlines.method_names())
        for timing in entry["results"].values():
            assert timing["median_us"] > 0
            assert timing["us_per_beam"] == pytest.approx(timing["median_us"] / entry["n_beams"])
    assert set(scaling["exponent"]) == set(scanlines.method_names())


def test_quick_batch_and_profile(quick_run):
    _, folder = quick_run
    data = json.loads((folder / "out.json").read_text())
    assert [b["dataset"] for b in data["batch"]] == ["intel", "freiburg"]
    for entry in data["batch"]:
        for row in entry["results"].values():
            assert row["error"] is None
            assert row["loop_us"] > 0
            assert row["batch_us"] > 0
            assert row["ratio"] == pytest.approx(row["batch_us"] / row["loop_us"])
    profile = data["profile"]  # the page writer profiles adaptive
    assert profile["method"] == "adaptive"
    assert profile["cumulative"]
    assert all(f["where"].startswith("scanlines/") for f in profile["cumulative"])


def test_write_docs_to_docs_path(quick_run):
    out, folder = quick_run
    assert out.returncode == 0, out.stderr
    page = folder / "PERFORMANCE.md"
    text = page.read_text()
    assert "Generated" in text.split("## Machine")[0]
    assert "python -m tools.bench" in text.split("## Machine")[0]
    for heading in (
        "## Machine",
        "## Summary",
        "## Per dataset",
        "## Scaling with the number of beams",
        "## Extractor.batch vs the loop",
        "## Where the time goes",
    ):
        assert heading in text
    assert "CPU:" in text
    assert "OPENBLAS environment variables:" in text
    assert f"--out {page}" in text  # the command line used is recorded
    assert "| method | median us/scan | p90 us/scan | scans/s | x iepf |" in text
    # the numbers of the page are the numbers of the run
    data = json.loads((folder / "out.json").read_text())
    intel = data["datasets"][0]["results"]["iepf"]
    assert microseconds(intel["median_us"]) in text
    assert f"wrote {page}" in out.stdout


def test_reference_falls_back_to_first_method(tmp_path):
    path = tmp_path / "out.json"
    out = run(
        "--quick", "-m", "pdbs", "-m", "adaptive", "-s", "lms_1deg", "--beams", "100",
        "--beams", "300", "--no-batch", "--json", str(path),
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    data = json.loads(path.read_text())
    assert data["methods"] == ["pdbs", "adaptive"]
    assert data["reference"]["method"] == "pdbs"
    assert "iepf is not selected" in data["reference"]["note"]
    assert "iepf is not selected" in out.stdout
    for dataset in data["datasets"]:
        assert set(dataset["results"]) == {"pdbs", "adaptive"}
        assert dataset["results"]["pdbs"]["ratio"] == 1.0
    assert [e["n_beams"] for e in data["scaling"]["entries"]] == [100, 300]
    assert data["batch"] == []
    assert data["profile"] is None


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--method", "no_such_method"], "unknown method 'no_such_method'"),
        (["--sensor", "no_such_sensor"], "unknown sensor preset"),
        (["--beams", "1"], "beam counts"),
        (["--repeats", "0"], "repeats"),
    ],
)
def test_bad_input_exits_2_with_one_line(args, message):
    out = run("--quick", *args)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("scanlines: error:")
    assert message in lines[0]
    assert out.stdout == ""


class Boom(Iepf):
    """Fails from its second call on."""

    name = "boom"
    calls = 0

    def extract(self, *args):
        type(self).calls += 1
        if type(self).calls >= 2:
            raise RuntimeError("boom on purpose")
        return super().extract(*args)


def test_failing_method_is_reported_not_fatal(monkeypatch):
    monkeypatch.setitem(REGISTRY, "boom", Boom)
    config = measure.BenchConfig.quick_config(
        methods=("iepf", "boom"), sensors=("lms_1deg",), beam_counts=(100,)
    )
    result = measure.run(config)
    for dataset in result.datasets:
        assert dataset.timings["iepf"].ok
        assert dataset.timings["boom"].status == "error"
        assert "RuntimeError: boom on purpose" in dataset.timings["boom"].error
        assert dataset.timings["boom"].ratio is None
    assert result.batch[0].rows["boom"].error is not None
    data = result.to_dict()
    json.dumps(data, allow_nan=False)
    assert data["datasets"][0]["results"]["boom"]["median_us"] is None
    page = render_markdown(result)
    assert "boom on purpose" in page
    assert "| boom | error |" in page


def test_import_needs_no_rich():
    code = (
        "import sys, scanlines.bench.measure, tools.bench.performance_page; "
        "print(sorted(m for m in sys.modules if m.startswith(('rich', 'matplotlib', 'typer'))))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=REPOSITORY, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "[]"


def test_quick_pipeline_section(quick_run):
    """The stages of `run`, end to end per format, jobs with the load, and the floor."""
    out, folder = quick_run
    assert out.returncode == 0, out.stderr
    pipeline = json.loads((folder / "out.json").read_text())["pipeline"]
    assert pipeline["scans"] == 20  # --quick
    assert pipeline["method"] == "adaptive"
    stages = pipeline["stages_us"]
    for stage in ("read and parse", "extract (batch)", "extract (loop)", "encode JSON Lines"):
        assert stages[stage] > 0
    assert set(pipeline["end_to_end"]) == {".jsonl", ".csv", ".mcap"}
    assert all(rate > 0 for rate in pipeline["end_to_end"].values())
    assert list(pipeline["jobs"]) == ["1"]
    assert pipeline["jobs_scans"] == 8 * 20  # the log repeated: many chunks in a full run
    assert len(pipeline["load_before"]) == 3
    assert 0.0 <= pipeline["other_cores_busy"] <= os.cpu_count()
    assert 0 < pipeline["floor_us"] < stages["extract (batch)"]
    assert pipeline["cold"] is None  # not in --quick: a fresh process per method
    page = (folder / "PERFORMANCE.md").read_text()
    assert "What a run costs besides the kernels" in page
    assert "one pass over the returns (floor)" in page
