"""A method added from outside the package runs everywhere a built-in one does.

``docs/ARCHITECTURE.md`` walks through this file: a toy method of a few dozen lines,
registered from here, goes through ``extract``, ``Extractor``, ``Extractor.batch``,
``scanlines eval`` and a writer, with no change to the package.
"""

from __future__ import annotations

import json
from typing import ClassVar

import numpy as np
import pytest
from typer.testing import CliRunner

from scanlines import Extractor, ParameterError, extract, method_info, method_names
from scanlines.cli import app
from scanlines.data import sample
from scanlines.io import open_log
from scanlines.methods import ClusteredMethod, register, unregister
from scanlines.params import Param, Settings, number
from scanlines.runs.runner import run_log_to_file
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import CLUSTERING
from scanlines.steps.events import EVENTS


class ChordSplit(ClusteredMethod):
    """Toy method: each cluster is one segment, or two halves when its middle return is
    farther than ``bulge`` from the chord of its ends."""

    name = "chord_split"
    settings: ClassVar[Settings] = Settings(
        clustering=CLUSTERING,
        segments={
            "bulge": Param(0.1, number(low=0.0, low_open=True), "largest bulge of one segment (m)")
        },
        events=EVENTS,
        output=output_settings(3),
    )

    def find_runs(self, returns, gap, start, end):
        a, b, group = [], [], []
        for c, (first, last) in enumerate(zip(start.tolist(), end.tolist(), strict=True)):
            middle = (first + last) // 2
            if (
                last - first >= 4
                and self._bulge(returns, first, middle, last) > self.params["bulge"]
            ):
                a += [first, middle + 1]
                b += [middle, last]
                group += [c, c]
            else:
                a.append(first)
                b.append(last)
                group.append(c)
        none = np.zeros(0, dtype=np.int64)
        return np.array(a), np.array(b), np.array(group), none

    @staticmethod
    def _bulge(returns, first: int, middle: int, last: int) -> float:
        x, y = returns.x, returns.y
        dx, dy = x[last] - x[first], y[last] - y[first]
        cross = dx * (y[middle] - y[first]) - dy * (x[middle] - x[first])
        return abs(cross) / max(np.hypot(dx, dy), 1e-12)


@pytest.fixture
def chord_split():
    register(ChordSplit)
    yield ChordSplit.name
    unregister(ChordSplit.name)


@pytest.fixture
def intel_scans():
    return list(open_log(sample("intel")))[:20]


def test_a_registered_method_is_listed_and_described(chord_split):
    assert chord_split in method_names()
    info = method_info(chord_split)
    assert info["doc"].startswith("A method added from outside")
    assert info["params"]["bulge"][:2] == (0.1, "largest bulge of one segment (m)")
    with pytest.raises(ParameterError, match="bulge must be a number in"):
        Extractor(chord_split, bulge=-1)


def test_extract_extractor_and_batch_agree(chord_split, intel_scans):
    extractor = Extractor(chord_split, bulge=0.05)
    scan = intel_scans[0]
    single = extractor(scan)
    assert len(single) > 3
    assert single.method == chord_split
    assert extract(scan, chord_split, bulge=0.05).first.tolist() == single.first.tolist()
    stack = np.stack([s.ranges for s in intel_scans])
    batched = extractor.batch(
        stack, scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max
    )
    for one, many in zip((extractor(s) for s in intel_scans), batched, strict=True):
        assert one.first.tolist() == many.first.tolist()
        np.testing.assert_array_equal(one.lines, many.lines)
        assert one.corners.tolist() == many.corners.tolist()


def test_scanlines_eval_scores_it(chord_split, tmp_path):
    out = tmp_path / "eval"
    result = CliRunner().invoke(
        app,
        [
            "eval",
            "sim",
            "-m",
            chord_split,
            "-m",
            "iepf",
            "-s",
            "lms_1deg",
            "-n",
            "3",
            "--out",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    assert chord_split in result.output
    assert any(chord_split in path.read_text() for path in out.glob("*.csv"))


def test_a_writer_writes_it(chord_split, tmp_path):
    target = tmp_path / "features.jsonl"
    summary = run_log_to_file(
        open_log(sample("intel")), Extractor(chord_split), target, scans=slice(0, 5)
    )
    assert summary.scans == 5
    rows = [json.loads(line) for line in target.read_text().splitlines()]
    assert len(rows) == 5
    assert all(row["segments"] for row in rows)
    assert (
        json.loads(target.with_name("features.jsonl.meta.json").read_text())["method"]
        == chord_split
    )
