"""``python -m tools.reproduce``: RESULTS.md, the label scoring, the paper's measures."""

from __future__ import annotations

import math
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from scanlines import Extraction, Extractor, Scan
from scanlines.data import sample
from scanlines.evaluation.cases import Case, line_similarity, score_case, score_labelled
from scanlines.evaluation.metrics import accuracy_rate, environmental_similarity
from scanlines.evaluation.scores import Tolerances
from scanlines.evaluation.specs import parse_specs
from scanlines.io import open_log
from tools.reproduce.experiments import PAPER_SPEED_RATIO, Headline, headline, run_dataset
from tools.reproduce.results_page import verdict_similarity, verdict_speed

pytestmark = pytest.mark.slow  # the experiments end to end


@dataclass(frozen=True)
class Frame:
    """A stand-in for ``scanlines.data.labels.LabelledFrame``."""

    scan: int
    breakpoints: tuple[int, ...] = ()
    corners: tuple[int, ...] = ()
    uncertain_breakpoints: tuple[int, ...] = ()
    uncertain_corners: tuple[int, ...] = ()
    notes: str = ""


# --------------------------------------------------------------------------- the command


REPOSITORY = Path(__file__).parents[1]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce")
    proc = subprocess.run(
        [sys.executable, "-m", "tools.reproduce", "--quick", "--out", str(out)],
        cwd=REPOSITORY,
        capture_output=True,
        text=True,
        timeout=300,
    )
    return proc, out


def test_quick_run_writes_results_with_every_section(quick_run):
    proc, out = quick_run
    assert proc.returncode == 0, proc.stderr
    text = (out / "RESULTS.md").read_text()
    assert f"Generated** by `python -m tools.reproduce --quick --out {out}`" in text
    assert "never edited by hand" in text
    for heading in (
        "## Headline: the paper's two claims, measured",
        "## 1. Table 1 analogue",
        "### 1a. Hand-labelled Intel frames (2)",
        "### 1b. Simulated Intel-like scans (3, lms_1deg)",
        "## 2. Table 3 analogue",
        "### 2a. Simulated TiM571 scans (3, the paper's sensor)",
        "## 3. Fig. 13 analogue",
        "## 4. All methods on simulated ground truth",
    ):
        assert heading in text
    # the tolerances are stated, for labels and for simulated truth
    assert "one-to-one within +-2 beams" in text
    assert "uncertain labels are don't care" in text
    assert "tolerances: events +-2 beams; segments |drho| <= 5 cm" in text
    assert "**Machine (every time below):**" in text
    # every method and the literal paper preset appear in the ground-truth table
    for label in ("adaptive", "adaptive:paper", "iepf", "pdbs", "hough"):
        assert f"| tim571 | {label} |" in text
    # the headline states both claims and a verdict on each excerpt
    assert "- **intel** (20 scans), adaptive (default) vs iepf" in text
    assert "- **freiburg** (20 scans), adaptive (default) vs iepf" in text


def test_quick_run_writes_the_figures_it_links(quick_run):
    proc, out = quick_run
    assert proc.returncode == 0, proc.stderr
    text = (out / "RESULTS.md").read_text()
    for name in ("fig13_similarity.png", "fig13_segments.png", "ground_truth_bars.png"):
        path = out / "figures" / name
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert path.stat().st_size < 400_000
        assert f"(figures/{name})" in text
    # the command prints the headline numbers
    assert "similarity error adaptive" in proc.stdout
    assert "paper: 4" in proc.stdout


def test_bad_option_is_one_line_and_exit_2(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "tools.reproduce",
            "--quick",
            "--scenes-per-sensor",
            "0",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        cwd=REPOSITORY,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().startswith("scanlines: error: scenes per sensor")
    assert not (tmp_path / "RESULTS.md").exists()


def test_import_needs_no_plotting_or_console_libraries():
    code = (
        "import sys, tools.reproduce; "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'rich')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=REPOSITORY, capture_output=True, text=True, timeout=60
    )
    assert out.stdout.strip() == "[]", out.stderr


# --------------------------------------------------------------------------- scoring


def test_uncertain_labels_are_dont_care():
    found = [10, 20, 31, 50]
    certain = [10, 30, 70]
    uncertain = [50, 90]
    s = score_labelled(found, certain, uncertain, tolerance=2, n_beams=180)
    # 10-10 and 31-30 are true positives; 50-50 matches an uncertain label (ignored);
    # 20 matches nothing (false positive); 70 is missed (false negative); 90 is
    # uncertain, so missing it costs nothing.
    assert (s.tp, s.fp, s.fn, s.found_ignored) == (2, 1, 1, 1)
    assert s.precision == pytest.approx(2 / 3)
    assert s.recall == pytest.approx(2 / 3)


def test_matching_is_one_to_one_and_within_tolerance():
    # two detections next to one label: one matches, the other is false; 3 beams is too far
    s = score_labelled([40, 41, 63], [40, 60], tolerance=2, n_beams=180)
    assert (s.tp, s.fp, s.fn) == (1, 2, 1)
    assert s.mean_offset == 0.0
    # without labels every detection is false and recall is undefined
    empty = score_labelled([5], [], tolerance=2, n_beams=180)
    assert (empty.tp, empty.fp, empty.fn) == (0, 1, 0)
    assert math.isnan(empty.recall)


def test_accuracy_rate_matches_the_papers_table_3():
    # Table 3 rows as (actual bp, actual corners, bp IEPF, bp proposed, corners IEPF,
    # corners proposed, accuracy IEPF %, accuracy proposed %)
    rows = [
        (6, 8, 6, 6, 10, 8, 85.71, 100.0),
        (8, 4, 8, 9, 4, 4, 100.0, 91.67),
        (12, 6, 9, 12, 7, 7, 77.78, 94.44),
    ]
    for bp, c, bp_i, bp_p, c_i, c_p, acc_i, acc_p in rows:
        assert round(100 * accuracy_rate(bp_i, bp, c_i, c), 2) == acc_i
        assert round(100 * accuracy_rate(bp_p, bp, c_p, c), 2) == acc_p
    # it only compares counts: detections all in the wrong place still score 1
    assert accuracy_rate(3, 3, 0, 0) == 1.0


def _one_segment(first: int, last: int, rho: float, alpha: float, bps, corners) -> Extraction:
    return Extraction(
        first=np.array([first]),
        last=np.array([last]),
        n_points=np.array([last - first + 1]),
        lines=np.array([[rho, alpha, 0, 0, 0, 0, 0]]),
        covariances=np.zeros((1, 2, 2)),
        breakpoints=np.array(bps, dtype=np.intp),
        corners=np.array(corners, dtype=np.intp),
        outliers=np.zeros(0, dtype=np.intp),
        method="hand",
        params={},
    )


def test_score_case_on_labels_counts_certain_labels_and_distances():
    # 11 beams on the wall x = 1 (every point at distance 0 from rho = 1, alpha = 0),
    # except beam 5, which is 10 cm behind the wall.
    angles = np.linspace(-0.5, 0.5, 11)
    ranges = 1.0 / np.cos(angles)
    ranges[5] = 1.1
    scan = Scan(ranges, angle_min=-0.5, angle_increment=0.1)
    labels = Frame(0, breakpoints=(2, 8), corners=(5,), uncertain_corners=(9,))
    case = Case("hand #0", scan, labels=labels)
    extraction = _one_segment(0, 10, 1.0, 0.0, bps=[2, 4], corners=[9])
    s = score_case(case, "hand", extraction, Tolerances())
    assert (s.bp.tp, s.bp.fp, s.bp.fn) == (1, 1, 1)  # 2 found, 4 is 4 beams from 8
    assert (s.corners.tp, s.corners.fp, s.corners.fn, s.corners.found_ignored) == (0, 0, 1, 1)
    assert (s.bp_actual, s.c_actual, s.bp_dont_care, s.c_dont_care) == (2, 1, 0, 1)
    # accuracy rate on certain labels: 1 - (|2 - 2| + |1 - 1|) / 3
    assert s.accuracy == 1.0
    assert s.similarity.n_points == 11
    assert s.similarity.mean == pytest.approx(0.1 / 11)
    assert s.similarity.max_distance == pytest.approx(0.1)
    assert s.covered_points == 11


def test_line_similarity_is_the_metrics_similarity_when_lines_are_finite():
    scans = list(open_log(sample("intel")))[:5]
    for method in ("adaptive", "iepf", "pdbs"):
        ex = Extractor(method)
        for scan in scans:
            e = ex(scan)
            ours, covered, nonfinite = line_similarity(e, scan)
            theirs = environmental_similarity(e, scan)
            assert nonfinite == 0
            assert ours.n_points == theirs.n_points
            assert ours.sum_distance == pytest.approx(theirs.sum_distance)
            assert covered <= ours.n_points


def test_line_similarity_leaves_out_segments_without_a_line():
    scan = Scan(np.ones(20), angle_min=-0.5, angle_increment=0.05)
    e = _one_segment(0, 19, math.nan, math.nan, [], [])
    sim, covered, nonfinite = line_similarity(e, scan)
    assert (sim.n_points, covered, nonfinite) == (0, 0, 1)


# --------------------------------------------------------------------------- headline


def test_headline_returns_the_similarity_gain_and_the_speed_ratio():
    scans = list(open_log(sample("intel")))[:4]
    run = run_dataset(
        "intel",
        "test",
        [Case(f"intel #{i}", s) for i, s in enumerate(scans)],
        parse_specs(["adaptive", "iepf"]),
        repeats=1,
        tol=Tolerances(),
    )
    h = headline(run)
    a, b = run.summary("adaptive"), run.summary("iepf")
    assert h.similarity_mm == pytest.approx(1000 * a.similarity.mean)
    assert h.reference_similarity_mm == pytest.approx(1000 * b.similarity.mean)
    expected = 100 * (h.reference_similarity_mm - h.similarity_mm) / h.reference_similarity_mm
    assert h.similarity_gain_pct == pytest.approx(expected)
    assert h.speed_ratio == pytest.approx(b.median_us / a.median_us)
    assert math.isfinite(h.similarity_gain_pct)
    assert h.speed_ratio > 0
    assert run.samples_ns["adaptive"].shape == (1, 4)


def _headline(gain: float, ratio: float) -> Headline:
    return Headline("x", 1, "adaptive", "iepf", 1.0, 1.0, gain, 1.0, 1.0, ratio)


def test_verdicts_say_plainly_when_a_claim_does_not_reproduce():
    assert verdict_speed(_headline(0, 0.25)).startswith("does not reproduce: 4.00x slower")
    assert verdict_speed(_headline(0, 2.0)).startswith("faster, but not 4x")
    assert verdict_speed(_headline(0, PAPER_SPEED_RATIO)).startswith("reproduces")
    assert verdict_similarity(_headline(-5.0, 1)).startswith("does not reproduce")
    assert verdict_similarity(_headline(3.0, 1)).startswith("same direction, smaller")
    assert verdict_similarity(_headline(10.0, 1)).startswith("reproduces")
