"""Fuzzing the log readers, the map commands, the files that set things and the ROS 2
node: past failures stay fixed, and seeded mutations find no defect.

Every log input is read through the library (fail and skip modes) and the ``info`` and
``run`` commands, every map input (a log's poses, a TUM file) through ``map`` and ``eval
--map``, in worker processes with a timeout and a memory limit (see ``channels.py``,
``map_channels.py``); every DDS sample is sent to one running ROS 2 node
(``dds_target.py``). A failure lists each defect as ``format | mutator | channel | error |
message | input``. ``pytest --long`` runs the long mutation campaign (logs and maps)
instead of the short one of the logs.
"""

from __future__ import annotations

import os
from collections import Counter
from pathlib import Path

import pytest

from dds_domains import free_domain

from .make_corpus import GENERATED, build_generated, corpus_inputs
from .run import Case, fuzz, replay, report

pytestmark = pytest.mark.slow  # thousands of damaged inputs

SHORT_RUN = 300
MAP_RUN = 45
SETTINGS_RUN = 90
DDS_SHORT_RUN = 200
LONG_RUN = 5000
SEED = 1
JOBS = max(1, min(2, len(os.sched_getaffinity(0))))


def fail_on_defects(cases: list[Case], *, kinds: bool = True) -> None:
    """Fail listing every defect: format | mutator | channel | error | message | input."""
    if any(case.defects for case in cases):
        pytest.fail("defects found:\n" + report(cases, kinds=kinds), pytrace=False)


@pytest.fixture(scope="module")
def corpus_cases(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Case]:
    """Every corpus input (and the generated one) read through every channel, by name."""
    generated = build_generated(tmp_path_factory.mktemp("generated"))
    cases = replay(corpus_inputs() + generated, jobs=JOBS)
    return {case.path.name: case for case in cases}


CORPUS_NAMES = [p.name for p in corpus_inputs()] + list(GENERATED)


@pytest.mark.parametrize("name", CORPUS_NAMES)
def test_corpus_input_reads_cleanly(corpus_cases: dict[str, Case], name: str) -> None:
    fail_on_defects([corpus_cases[name]], kinds=False)


def test_short_mutation_run(request: pytest.FixtureRequest, tmp_path: Path) -> None:
    """The log target alone. Reproduce with ``python -m tests.fuzz.run --count 300 --seed
    1 --targets logs``; the defective inputs are kept in this test's ``tmp_path``."""
    if request.config.getoption("--long"):
        pytest.skip("the long run covers these inputs (the first of the same seed)")
    failures = tmp_path / "failures"
    cases = fuzz(SHORT_RUN, SEED, targets=("logs",), jobs=JOBS, save_failures=failures)
    assert len(cases) == SHORT_RUN
    fail_on_defects(cases)


def test_short_map_run(tmp_path: Path) -> None:
    """The map target alone, bounded: 45 inputs (15 of each map seed: shifted, damaged and
    jumping poses, TUM files with duplicates, huge or non-finite fields) through ``map``
    and ``eval --map``. Reproduce with ``python -m tests.fuzz.run --count 45 --seed 1
    --targets maps``."""
    cases = fuzz(MAP_RUN, SEED, targets=("maps",), jobs=JOBS, save_failures=tmp_path / "failures")
    assert len(cases) == MAP_RUN
    assert {o.channel for case in cases for o in case.outcomes} == {"map", "eval map"}
    fail_on_defects(cases)


def test_short_settings_files_run(tmp_path: Path) -> None:
    """The settings-file targets, bounded: 90 inputs (30 each of parameters files and
    configurations, sensor profiles and line maps: alias bombs, deep nesting, huge
    integers, booleans, lines off their ends) read and run. Reproduce with ``python -m
    tests.fuzz.run --count 90 --seed 1 --targets params profiles linemaps``."""
    targets = ("params", "profiles", "linemaps")
    failures = tmp_path / "failures"
    cases = fuzz(SETTINGS_RUN, SEED, targets=targets, jobs=JOBS, save_failures=failures)
    assert len(cases) == SETTINGS_RUN
    assert {case.seed_name for case in cases} == {
        "params-yaml", "config-toml", "profile-json", "line-map",
    }  # fmt: skip
    fail_on_defects(cases)


@pytest.mark.long
def test_long_mutation_run(request: pytest.FixtureRequest, tmp_path: Path) -> None:
    """``python -m tests.fuzz.run --count 5000 --seed 1 --jobs N``: 1,000 inputs each of the
    logs, maps, params, profiles and linemaps targets."""
    if not request.config.getoption("--long"):
        pytest.skip("a long run: give pytest --long")
    jobs = max(1, len(os.sched_getaffinity(0)))
    cases = fuzz(LONG_RUN, SEED, jobs=jobs, save_failures=tmp_path / "failures")
    assert len(cases) == LONG_RUN
    fail_on_defects(cases)


DDS_CORPUS = Path(__file__).parent / "corpus_dds"


def test_dds_corpus_samples_are_handled_cleanly() -> None:
    """Samples that once failed the node (``corpus_dds/README.md``), sent to a running one."""
    samples = sorted(DDS_CORPUS.glob("*.cdr"))
    assert len(samples) >= 2
    cases = replay(samples, domain=free_domain())
    assert len(cases) == len(samples)
    fail_on_defects(cases)


def test_dds_short_run(tmp_path: Path) -> None:
    """Mutated LaserScan samples sent to one ROS 2 node over loopback DDS: it survives
    each (a good scan is still published after), and exits on SIGTERM with its summary.
    Reproduce with ``python -m tests.fuzz.run --count 200 --seed 1 --targets dds``."""
    failures = tmp_path / "failures"
    domain = free_domain()  # one no other process (a campaign, another clone) uses
    cases = fuzz(DDS_SHORT_RUN, SEED, targets=("dds",), save_failures=failures, domain=domain)
    assert len(cases) == DDS_SHORT_RUN
    fail_on_defects(cases)
    outcomes = [outcome for case in cases for outcome in case.outcomes]
    assert [o.summary for o in outcomes if o.channel == "node exit"] == ["exit 143"]
    seen = Counter(o.error for o in outcomes)
    for kind in ("published", "malformed scan", "undecodable", "dropped by DDS"):
        assert seen[kind] > 0, seen
