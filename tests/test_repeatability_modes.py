"""``eval --real``: the bare mode, the fidelity of long segments and the pairs ``--pairs``
scores (issue 39's measurement side)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import scanlines
from scanlines import Extractor, Scan
from scanlines.evaluation.repeat_pairs import pair_slots
from scanlines.evaluation.repeat_scores import segment_fidelity
from scanlines.evaluation.repeatability import (
    RepeatTolerances,
    candidate_pairs,
    register_pairs,
    repeatability,
    repeatability_of_scans,
)
from scanlines.evaluation.specs import MethodSpec
from scanlines.io import open_log
from scanlines.sensor.profile import estimate_profile
from scanlines.sim import random_scene, simulate

DATA = Path(__file__).parents[1] / "src" / "scanlines" / "data"
INTEL = DATA / "intel_excerpt.clf.gz"


# --------------------------------------------------------------------------- fidelity


def test_fidelity_by_hand():
    wall = np.array([[0.0, 0.0, 2.0, 0.0]])
    near = [(0.2, 0.01), (0.6, -0.01), (1.0, 0.02), (1.4, -0.02), (1.8, 0.0)]
    away = [(-0.1, 0.0), (2.1, 0.0), (1.0, 0.15), (1.2, -0.11)]  # beyond the ends; > 10 cm
    rms = math.sqrt((1e-4 + 1e-4 + 4e-4 + 4e-4 + 0.0) / 5)
    assert segment_fidelity(wall, np.array(near + away))[0] == pytest.approx(rms)
    # Reversed ends, and the same moved off the axes: the same figure.
    assert segment_fidelity(wall[:, [2, 3, 0, 1]], np.array(near))[0] == pytest.approx(rms)
    turn, shift = math.radians(35.0), np.array([3.0, -1.0])
    rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    moved_wall = np.concatenate([rotation @ wall[0, 0:2] + shift, rotation @ wall[0, 2:4] + shift])[
        None, :
    ]
    moved = np.array(near + away) @ rotation.T + shift
    assert segment_fidelity(moved_wall, moved)[0] == pytest.approx(rms)
    # Four returns near it are too few; a wider band takes the 11 and 15 cm ones too.
    assert math.isnan(segment_fidelity(wall, np.array(near[:4] + away))[0])
    wide = math.sqrt((1e-3 + 0.15**2 + 0.11**2) / 7)
    assert segment_fidelity(wall, np.array(near + away), band=0.2)[0] == pytest.approx(wide)


def zigzag_wall(offset: float) -> Scan:
    """A wall 2 m ahead seen over 200 beams at 0.5 deg, its returns alternately ``offset``
    in front of and behind it, in a pattern symmetric about the middle beam: every
    least-squares line of all of them is the wall itself, and their rms distance to it is
    ``offset`` exactly."""
    step, half = math.radians(0.5), (np.arange(100) + 0.5) * math.radians(0.5)
    bearings = np.concatenate((math.pi / 2 - half[::-1], math.pi / 2 + half))
    sign = np.concatenate(((-1.0) ** np.arange(100)[::-1], (-1.0) ** np.arange(100)))
    ranges = (2.0 + sign * offset) / np.sin(bearings)
    return Scan(ranges, bearings[0], step, 0.05, 30.0, pose=(0.0, 0.0, 0.0))


@pytest.mark.parametrize("offset", [0.004, 0.01])
def test_fidelity_of_a_constructed_wall(offset):
    # Three copies: each of the 3 pairs gives both directions one long segment whose line is
    # the wall, with the other copy's 200 returns at +-offset from it. (ICP keeps the
    # copies where they are while every return has a local line: up to 1 cm of zigzag.)
    scans = [(k, zigzag_wall(offset)) for k in range(3)]
    result = repeatability_of_scans(scans, ["iepf", "partition"])
    assert [p.pose for p in result.pairs] == [(0.0, 0.0, 0.0)] * 3
    for method in result.methods:
        assert method.fidelity_segments == 6
        assert method.fidelity_mm == pytest.approx(1000 * offset, rel=1e-5)
        assert method.strict == 1.0
    # Only the fidelity's band decides: a band narrower than the offset leaves no returns.
    narrow = RepeatTolerances(fidelity_band=offset / 2)
    for method in repeatability_of_scans(scans, ["iepf"], tol=narrow).methods:
        assert method.fidelity_segments == 0
        assert math.isnan(method.fidelity_mm)


# --------------------------------------------------------------------------- modes


class Recorder:
    """Stands in for ``MethodSpec.extractor``: records each extractor made (its profile)
    and the scans it is fed, in order."""

    def __init__(self, monkeypatch):
        self.made: list[tuple[str, object, list[int]]] = []
        original = MethodSpec.extractor
        recorder = self

        def extractor(spec, sensor_profile=None):
            real = original(spec, sensor_profile=sensor_profile)
            fed: list[int] = []
            recorder.made.append((spec.label, sensor_profile, fed))

            def call(scan):
                fed.append(id(scan))
                return real(scan)

            return call

        monkeypatch.setattr(MethodSpec, "extractor", extractor)


def excerpt(n: int) -> list[tuple[int, Scan]]:
    return list(open_log(INTEL).enumerate())[:n]


def test_bare_mode_feeds_one_extractor_per_method_the_pairs_scans_in_log_order(monkeypatch):
    scans = excerpt(40)
    recorder = Recorder(monkeypatch)
    tol = RepeatTolerances(max_pairs=8)
    result = repeatability_of_scans(scans, ["partition", "iepf"], tol=tol, bare=True)
    assert result.mode == "bare"
    assert result.profile is None
    assert "bare: no profile" in result.title()
    used = {r for p in result.used_pairs for r in (p.i, p.j)}
    in_order = [id(scan) for record, scan in scans if record in used]
    assert len(result.used_pairs) == 8
    working = [made for made in recorder.made if made[2]]  # parse_specs makes one to check
    assert [(label, profile) for label, profile, _ in working] == [
        ("partition", None),
        ("iepf", None),
    ]
    for _, _, fed in working:
        assert fed == in_order
    assert result.scans == len(in_order)


def test_profiled_mode_measures_the_profile_run_measures(monkeypatch):
    scans = excerpt(40)
    recorder = Recorder(monkeypatch)
    result = repeatability_of_scans(scans, ["partition"], tol=RepeatTolerances(max_pairs=8))
    expected = estimate_profile(scan for _, scan in scans)
    assert result.mode == "profiled"
    assert result.profile == expected
    assert [profile for _, profile, fed in recorder.made if fed] == [expected]
    assert f"{1000 * expected.noise_sigma0:.1f} mm" in result.title()


def test_bare_and_profiled_figures_are_those_of_their_extractors():
    tol = RepeatTolerances(max_pairs=8)
    bare = repeatability(INTEL, ["partition"], 40, tol=tol, bare=True)
    profiled = repeatability(INTEL, ["partition"], 40, tol=tol)
    assert [p.used for p in bare.pairs] == [p.used for p in profiled.pairs]
    used = {r for p in bare.used_pairs for r in (p.i, p.j)}
    scans = [scan for record, scan in excerpt(40) if record in used]
    profile = estimate_profile(scan for _, scan in excerpt(40))
    for result, extractor in (
        (bare, Extractor("partition")),
        (profiled, Extractor("partition", sensor_profile=profile)),
    ):
        assert result.methods[0].segments == sum(len(extractor(scan)) for scan in scans)
    # The profile changes partition's segments on this excerpt: the modes differ.
    assert bare.methods[0].segments != profiled.methods[0].segments
    row = bare.summary_rows()[0]
    assert row["mode"] == "bare"
    assert row["fidelity_segments"] > 0
    assert 1.0 < row["fidelity_mm"] < 30.0


def test_bare_mode_takes_no_profile():
    scans = excerpt(6)
    profile = estimate_profile(scan for _, scan in scans)
    with pytest.raises(ValueError, match="no sensor profile"):
        repeatability_of_scans(scans, ["iepf"], sensor_profile=profile, bare=True)
    assert repeatability_of_scans(scans, ["iepf"], sensor_profile=profile).mode == "given"


# --------------------------------------------------------------------------- pairs


def test_pair_slots_cut_the_candidates_in_order_and_cycle_the_gap():
    candidates = [(a, a + g) for a in range(100) for g in (1, 2, 3) if a + g < 100]
    slots = pair_slots(candidates, 10, 3)
    assert sorted(p for slot in slots for p in slot) == sorted(candidates)
    assert [slot[0][1] - slot[0][0] for slot in slots] == [1, 2, 3, 1, 2, 3, 1, 2, 3, 1]
    firsts = [min(a for a, _ in slot) for slot in slots]
    assert firsts == sorted(firsts)
    assert firsts[0] == 0
    assert firsts[-1] >= 85


def turning_log(n: int) -> list[tuple[int, Scan]]:
    """``n`` scans of one room from one place, every odd one turned round (180 deg, so it
    sees the other half of the room): only pairs two records apart share a view."""
    scene = random_scene(1, "lms_1deg", kind="room")
    x, y, theta = scene.pose
    scans = []
    for k in range(n):
        turned = (x, y, theta + math.pi * (k % 2))
        scans.append((k, simulate(scene.world, scene.sensor, turned, seed=k).scan))
    return scans


def test_max_pairs_scores_that_many_used_pairs_spread_over_the_log():
    scans = turning_log(60)
    tol = RepeatTolerances(max_pairs=10)
    pairs, source = register_pairs(scans, tol)
    used = [p for p in pairs if p.used]
    assert source == "log poses + ICP"
    assert len(used) == 10
    assert {p.j - p.i for p in used} == {2}
    assert all(p.j - p.i != 2 for p in pairs if not p.used)
    starts = [p.i for p in used]
    assert starts[0] <= 5
    assert starts[-1] >= 50
    assert min(np.diff(starts)) >= 2
    assert len(candidate_pairs(scans, tol)) == 59 + 58 + 57


# --------------------------------------------------------------------------- command


def test_eval_real_bare_writes_the_mode_and_the_fidelity(tmp_path):
    args = ["eval", "real", str(INTEL), "--scans", "30", "--pairs", "6", "-m", "iepf"]
    out = scanlines(*args, "--bare", "--out", "out", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "bare: no profile" in out.stdout
    assert "fidelity" in out.stdout
    with (tmp_path / "out" / "repeatability.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert rows[0]["mode"] == "bare"
    assert rows[0]["pairs_used"] == "6"
    assert 1.0 < float(rows[0]["fidelity_mm"]) < 30.0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sim", "--bare"], "--bare"),
        (["real", str(INTEL), "--bare", "--sensor-profile", "p.json"], "excludes"),
    ],
)
def test_bare_is_of_real_and_without_a_profile(args, message, tmp_path):
    (tmp_path / "p.json").write_text("{}")  # there, so that --bare's own check speaks
    out = scanlines("eval", *args, cwd=tmp_path)
    assert out.returncode == 2
    assert message in out.stderr
