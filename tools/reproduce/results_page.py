"""``RESULTS.md``: the page of ``python -m tools.reproduce``, written from a measured run.

:func:`render_markdown` turns a :class:`~tools.reproduce.experiments.ReproduceResult`
into the page: the machine and tolerances, the headline (the paper's two claims and a
plain verdict on each, :func:`verdict_similarity` and :func:`verdict_speed`), the
analogues of the paper's Tables 1 and 3 and Fig. 13, and every method on simulated
ground truth. Nothing is measured here.
"""

from __future__ import annotations

import math

import numpy as np

from scanlines.bench.timing import REFERENCE
from scanlines.evaluation.cases import label_tolerance_caption, point_distances
from scanlines.evaluation.evaluate import tolerance_caption
from scanlines.evaluation.scores import EventScore
from scanlines.report import MISSING, markdown_table, number, percent
from tools.reproduce.experiments import (
    FIG13_METHODS,
    FIG13_RULE,
    PAPER_BOUND,
    PAPER_SIMILARITY_GAIN,
    PAPER_SPEED_RATIO,
    DatasetRun,
    Headline,
    ReproduceResult,
    fig13_case,
    headline,
)

__all__ = ["render_markdown", "verdict_similarity", "verdict_speed"]


def _machine_line(result: ReproduceResult) -> str:
    m = result.machine
    cores = f"{m.get('cores_logical')} logical cores"
    if m.get("cores_usable") is not None:
        cores += f" ({m['cores_usable']} usable)"
    load, after = m.get("loadavg_before"), m.get("loadavg_after")
    load_text = f"; 1-min load average {load[0]:.2f} at the start" if load else ""
    if load and after:
        load_text += f", {after[0]:.2f} at the end"
    return (
        f"**Machine (every time below):** {m.get('cpu')}, {cores}, {m.get('platform')}, "
        f"{m.get('python')}, numpy {m.get('numpy')}{load_text}. All times were measured in "
        "this one process by one rule (`scanlines.bench.timing`): every timed extraction "
        "directly follows an untimed extraction of the same scan by the same method (whose "
        f"result is the one scored); per dataset {result.config.repeats} timed pass"
        f"{'es' if result.config.repeats != 1 else ''} over every scan, interleaved between "
        "methods; us/scan is the median of all samples (`time.perf_counter_ns`). Section 4 "
        "makes one pass: one sample per scan and method."
    )


def _event_pr(s: EventScore | None) -> tuple[str, str]:
    if s is None:
        return MISSING, MISSING
    return number(s.precision), number(s.recall)


def _table1(run_: DatasetRun, tol_text: str, dont_care: str) -> str:
    labels = run_.labels
    first = run_.scores[labels[0]]
    rows = []
    for j, case in enumerate(run_.cases):
        f = first[j]
        cells = [
            case.name,
            str(f.bp_actual),
            str(f.c_actual),
            f"{f.bp_dont_care} / {f.c_dont_care}",
        ]
        cells += [
            f"{run_.scores[lab][j].bp_found} / {run_.scores[lab][j].c_found}" for lab in labels
        ]
        rows.append(cells)
    totals = [run_.summary(lab) for lab in labels]
    rows.append(
        [
            "**total**",
            str(sum(f.bp_actual or 0 for f in first)),
            str(sum(f.c_actual or 0 for f in first)),
            f"{sum(f.bp_dont_care for f in first)} / {sum(f.c_dont_care for f in first)}",
            *[f"{t.bp_found} / {t.c_found}" for t in totals],
        ]
    )
    counts = markdown_table(
        [
            "frame",
            "actual bp",
            "actual corners",
            f"{dont_care} bp / c",
            *[f"{lab} bp / c" for lab in labels],
        ],
        rows,
    )
    pooled_rows = []
    for t in totals:
        bp, c = t.bp or EventScore(), t.corners or EventScore()
        pooled_rows.append(
            [
                t.label,
                str(t.bp_found),
                f"{bp.tp} / {bp.fp} / {bp.fn}",
                *_event_pr(t.bp),
                number(bp.f1),
                str(t.c_found),
                f"{c.tp} / {c.fp} / {c.fn}",
                *_event_pr(t.corners),
                number(c.f1),
                number(t.accuracy_mean, ".3f"),
            ]
        )
    pooled = markdown_table(
        [
            "method",
            "bp found",
            "bp TP / FP / FN",
            "bp P",
            "bp R",
            "bp F1",
            "corners found",
            "corner TP / FP / FN",
            "corner P",
            "corner R",
            "corner F1",
            "accuracy rate",
        ],
        pooled_rows,
    )
    detail_rows = []
    for j, case in enumerate(run_.cases):
        for lab in labels:
            f = run_.scores[lab][j]
            detail_rows.append(
                [
                    case.name,
                    lab,
                    f"{f.bp_found} / {f.bp_actual}",
                    *_event_pr(f.bp),
                    f"{f.c_found} / {f.c_actual}",
                    *_event_pr(f.corners),
                    number(f.accuracy, ".3f"),
                ]
            )
    detail = markdown_table(
        [
            "frame",
            "method",
            "bp found / actual",
            "bp P",
            "bp R",
            "corners found / actual",
            "corner P",
            "corner R",
            "accuracy rate",
        ],
        detail_rows,
        left=2,
    )
    return "\n".join(
        [
            "Counts per frame (found: `breakpoints / corners`):\n",
            counts,
            f"Matched, pooled over the {len(run_.cases)} frames (P = TP / (TP + FP), "
            "R = TP / (TP + FN); accuracy rate: the paper's count-based rate, mean over "
            f"frames). {tol_text}\n",
            pooled,
            "<details><summary>Per frame and method: matched precision and recall</summary>\n",
            tol_text + "\n",
            detail,
            "</details>\n",
        ]
    )


def _table3_truth(run_: DatasetRun, tol_text: str) -> str:
    rows = []
    for lab in run_.labels:
        t = run_.summary(lab)
        rows.append(
            [
                lab,
                f"{t.bp_found} / {t.bp_actual}",
                f"{t.c_found} / {t.c_actual}",
                number(t.accuracy_mean, ".3f"),
                *_event_pr(t.bp),
                *_event_pr(t.corners),
                number(1000 * t.similarity.mean, ".1f"),
                number(t.median_us, ",.0f"),
                number(run_.time_ratio(lab)),
            ]
        )
    table = markdown_table(
        [
            "method",
            "bp found / actual",
            "corners found / actual",
            "accuracy rate",
            "bp P",
            "bp R",
            "corner P",
            "corner R",
            "sim. error mm",
            "us/scan",
            "time / iepf",
        ],
        rows,
    )
    return (
        f"{len(run_.cases)} scans: {run_.title}. Found and actual counts are totals over the "
        "scans; accuracy rate: the paper's `1 - (|bp found - bp actual| + |c found - c "
        "actual|) / (bp actual + c actual)`, mean over scans (it compares counts only, so a "
        "detection in the wrong place is not seen); P and R: matched, pooled over scans; "
        "sim. error: mean point-to-line distance; us/scan: median; time / iepf: below 1 is "
        f"faster than iepf. {tol_text}\n\n" + table
    )


def _table3_paper_layout(run_: DatasetRun, method: str = "adaptive") -> str:
    rows = []
    ours, ref = run_.scores[method], run_.scores[REFERENCE]
    us_m, us_r = run_.per_scan_us(method), run_.per_scan_us(REFERENCE)
    for j, case in enumerate(run_.cases):
        a, b = ours[j], ref[j]
        rows.append(
            [
                case.name,
                str(a.bp_actual),
                str(a.c_actual),
                str(b.bp_found),
                str(a.bp_found),
                str(b.c_found),
                str(a.c_found),
                percent(b.accuracy),
                percent(a.accuracy),
                f"{us_r[j] / 1000:.2f}",
                f"{us_m[j] / 1000:.2f}",
            ]
        )
    return markdown_table(
        [
            "scan",
            "actual bp",
            "actual corners",
            "bp IEPF",
            f"bp {method}",
            "corners IEPF",
            f"corners {method}",
            "accuracy IEPF",
            f"accuracy {method}",
            "ms IEPF",
            f"ms {method}",
        ],
        rows,
    )


def _table3_real(run_: DatasetRun) -> str:
    n = len(run_.cases)
    rows = []
    for lab in run_.labels:
        t = run_.summary(lab)
        rows.append(
            [
                lab,
                number(t.bp_found / n, ".1f"),
                number(t.c_found / n, ".1f"),
                number(t.n_segments / n, ".1f"),
                number(1000 * t.similarity.mean, ".2f"),
                number(1000 * t.similarity.rms, ".2f"),
                percent(t.coverage),
                number(t.median_us, ",.0f"),
                number(t.p90_us, ",.0f"),
                number(run_.time_ratio(lab)),
            ]
        )
    return markdown_table(
        [
            "method",
            "bp / scan",
            "corners / scan",
            "segments / scan",
            "sim. error mm",
            "sim. RMS mm",
            "points on segments",
            "us/scan",
            "p90 us/scan",
            "time / iepf",
        ],
        rows,
    )


def _lower_higher(gain_pct: float) -> str:
    if not math.isfinite(gain_pct):
        return MISSING
    return f"{abs(gain_pct):.1f} % {'lower' if gain_pct >= 0 else 'higher'}"


def _nonfinite_note(run_: DatasetRun) -> str:
    parts = []
    for lab in run_.labels:
        t = run_.summary(lab)
        if t.nonfinite_lines:
            parts.append(
                f"{lab}: {t.nonfinite_lines} of {t.n_segments} segments "
                f"({100 * t.nonfinite_lines / t.n_segments:.0f} %)"
            )
    if not parts:
        return ""
    return (
        "Segments without a finite line are left out of the similarity error and of the "
        f"points on segments ({run_.name}: {'; '.join(parts)}).\n"
    )


def verdict_similarity(h: Headline) -> str:
    """Whether ``h`` reproduces the paper's similarity claim, in words."""
    g = h.similarity_gain_pct
    if not math.isfinite(g):
        return "cannot be computed"
    if g >= PAPER_SIMILARITY_GAIN:
        return f"reproduces: the error is {g:.1f} % lower (paper: {PAPER_SIMILARITY_GAIN} %)"
    if g > 0:
        return (
            f"same direction, smaller: the error is {g:.1f} % lower "
            f"(paper: {PAPER_SIMILARITY_GAIN} %)"
        )
    return f"does not reproduce: the error is {-g:.1f} % higher than IEPF's"


def verdict_speed(h: Headline) -> str:
    """Whether ``h`` reproduces the paper's speed claim, in words."""
    r = h.speed_ratio
    if not math.isfinite(r):
        return "cannot be computed"
    if r >= PAPER_SPEED_RATIO:
        return f"reproduces: {r:.2f}x faster than IEPF (paper: 4x)"
    if r > 1:
        return f"faster, but not 4x: {r:.2f}x faster than IEPF"
    return f"does not reproduce: {1 / r:.2f}x slower than IEPF (paper: 4x faster)"


def _headline_section(result: ReproduceResult) -> str:
    n_real = len(result.real[0].cases)
    scans_text = (
        f"all {n_real} shipped scans of each real excerpt"
        if result.config.real_scans is None
        else f"the first {n_real} scans of each real excerpt"
    )
    rows = []
    for run_ in result.real:
        for lab in ("adaptive", "adaptive:paper", REFERENCE):
            if lab not in run_.scores:
                continue
            t = run_.summary(lab)
            h = headline(run_, lab)
            n = len(run_.cases)
            rows.append(
                [
                    run_.name,
                    lab,
                    str(n),
                    number(h.similarity_mm, ".2f"),
                    MISSING if lab == REFERENCE else _lower_higher(h.similarity_gain_pct),
                    percent(t.coverage),
                    number(t.n_segments / n, ".1f"),
                    number(h.median_us, ",.0f"),
                    MISSING if lab == REFERENCE else f"{h.speed_ratio:.2f}",
                ]
            )
    table = markdown_table(
        [
            "excerpt",
            "method",
            "scans",
            "sim. error mm",
            "error vs IEPF",
            "points on segments",
            "segments / scan",
            "us/scan",
            "speed vs IEPF (IEPF time / time)",
        ],
        rows,
        left=2,
    )
    lines = []
    for h in result.headlines("adaptive"):
        lines.append(
            f"- **{h.dataset}** ({h.n_scans} scans), adaptive (default) vs iepf: similarity "
            f"error {h.similarity_mm:.2f} mm vs {h.reference_similarity_mm:.2f} mm, "
            f"{verdict_similarity(h)}; time {h.median_us:,.0f} us vs "
            f"{h.reference_median_us:,.0f} us per scan, {verdict_speed(h)}."
        )
    for h in (
        result.headlines("adaptive:paper") if "adaptive:paper" in result.labelled.scores else []
    ):
        lines.append(
            f"- **{h.dataset}**, adaptive:paper (the paper's text, literally) vs iepf: "
            f"{verdict_similarity(h)}; {verdict_speed(h)}."
        )
    return "\n".join(
        [
            "## Headline: the paper's two claims, measured\n",
            "The paper (sec. 4.4, 4.5 and Conclusions): its method's environmental similarity "
            f"is {PAPER_SIMILARITY_GAIN} % better than IEPF's, and it is four times faster "
            "than IEPF (4.6-9.2 ms against 19.4-39.7 ms per scan, MATLAB 2016b, Core "
            "i5-6300U). Here both are measured in the same run on the same scans: "
            f'{scans_text}. "Better similarity" is read as a smaller '
            "mean perpendicular distance of the points to their segment's line (the paper's "
            "Fig. 13 measure), pooled over all points of all segments of all scans.\n",
            *lines,
            "",
            table,
            "Read the similarity error with the coverage next to it: the measure only sees "
            "points that lie on a segment, so a method that drops more points (outliers, "
            "short clusters) or cuts walls into more, shorter segments scores lower without "
            "describing the room better. It needs no ground truth, which is why the matched "
            "scores of Tables 1 and 3 are the stronger evidence. The times compare our "
            "implementations, not the paper's MATLAB code: adaptive, iepf, pdbs and "
            "split_merge run as compiled kernels (C++), the other methods as numpy (see "
            "`docs/PERFORMANCE.md`).\n",
            *[_nonfinite_note(r) for r in result.real if _nonfinite_note(r)],
        ]
    )


def _fig13_section(result: ReproduceResult, figures: dict[str, str]) -> str:
    i, case = fig13_case(result)
    rows = []
    for lab in FIG13_METHODS:
        f = result.labelled.scores[lab][i]
        pieces = point_distances(result.labelled.extractions[lab][i], case.scan)
        d = np.concatenate([p[1] for p in pieces]) if pieces else np.zeros(0)
        d = d[np.isfinite(d)]
        over = float(np.mean(d > PAPER_BOUND)) if d.size else math.nan
        rows.append(
            [
                lab,
                str(f.n_segments),
                str(f.similarity.n_points),
                number(1000 * f.similarity.mean, ".2f"),
                number(1000 * f.similarity.max_distance, ".1f"),
                percent(over),
                f"{f.bp_found} / {f.bp_actual}",
                f"{f.c_found} / {f.c_actual}",
            ]
        )
    note = result.label_notes.get(result.fig13_frame, "")
    return "\n".join(
        [
            "## 3. Fig. 13 analogue: similarity error along one real frame\n",
            f'Frame: Intel excerpt scan {result.fig13_frame} (`list(open_log(sample("intel")))'
            f"[{result.fig13_frame}]`), {FIG13_RULE}."
            + (f" Label notes: {note}" if note else "")
            + " The paper's "
            "Fig. 13 shows the same curve for its own indoor scan (TiM571); its method stays "
            "under 2 cm.\n",
            f"![similarity error along the scan](figures/{figures['fig13']})\n",
            f"![the frame with each method's segments](figures/{figures['frame']})\n",
            markdown_table(
                [
                    "method",
                    "segments",
                    "points",
                    "mean mm",
                    "max mm",
                    "points > 2 cm",
                    "bp found / labelled",
                    "corners found / labelled",
                ],
                rows,
            ),
            "Distance: perpendicular distance of each point to the line of its segment "
            "(valid beams in the segment's index range, outliers excluded). Labelled counts "
            f"are certain labels. {label_tolerance_caption(result.config.tol)}\n",
        ]
    )


def _ground_truth_section(result: ReproduceResult, figures: dict[str, str]) -> str:
    ev = result.ground_truth
    cfg = ev.config
    rows = []
    for rec in ev.summaries:
        if rec.sensor == "all":
            continue
        s = rec.summary
        rows.append(
            [
                rec.sensor,
                rec.spec.label,
                number(s.breakpoints.f1, ".3f"),
                number(s.corners.f1, ".3f"),
                number(s.segments.true_pos, ".3f"),
                number(s.segments.false_pos, ".3f"),
                number(rec.median_us, ",.0f"),
            ]
        )
    return "\n".join(
        [
            "## 4. All methods on simulated ground truth\n",
            f"`scanlines.evaluation.evaluate.evaluate`: {cfg.n} scenes per sensor preset, seed "
            f"{cfg.seed}, noise {cfg.noise}; every method on the same scans. Rates pooled over "
            "scans; us/scan: median, one sample per scan. "
            f"{tolerance_caption(cfg.tol)}.\n",
            markdown_table(
                ["sensor", "method", "bp F1", "corner F1", "TruePos", "FalsePos", "us/scan"],
                rows,
                left=2,
            ),
            f"![ground-truth scores by sensor and method](figures/{figures['bars']})\n",
        ]
    )


def render_markdown(result: ReproduceResult, figures: dict[str, str]) -> str:
    """``RESULTS.md`` for ``result``; ``figures``: key -> file name in ``figures/``."""
    cfg = result.config
    tol = cfg.tol
    lab_text = label_tolerance_caption(tol)
    sim_text = tolerance_caption(tol) + "."
    labelled, t1, t3 = result.labelled, result.sim_table1, result.sim_table3
    settings = (
        f"{len(labelled.cases)} labelled Intel frames, {len(t1.cases)} simulated scenes for "
        f"Tables 1 and 3, {len(result.real[0].cases)} scans of each real excerpt, "
        f"{result.ground_truth.config.n} scenes per sensor for section 4, "
        f"{cfg.repeats} timed repeat{'s' if cfg.repeats != 1 else ''}, seed {cfg.seed}"
        + (" (**--quick run**)" if cfg.quick else "")
    )
    parts = [
        "# Results: the paper's experiments, reproduced\n",
        f"<!-- Generated by `{result.command}`. Do not edit: rerun the command. -->\n",
        f"> **Generated** by `{result.command}` (`tools.reproduce`) on "
        f"{result.started[:10]} in {result.elapsed_s:.0f} s; never edited by hand: rerun the "
        "command to update. Data: only what the repository ships (the Intel and Freiburg "
        "excerpts of `scanlines.data`, the hand labels `scanlines/data/intel_labels.json`, "
        f"and the scan simulator). Settings: {settings}.\n",
        f"Methods: {', '.join(f'`{s.label}`' for s in result.specs)}, default parameters "
        "(`adaptive:paper` is the paper's text taken literally; `adaptive` is the project's "
        'default reading, see the README). Paper: "An Adaptive Threshold Line Segment '
        'Feature Extraction Algorithm for Laser Radar Scanning Environments", Electronics '
        "11(11), 1759, 2022.\n",
        _machine_line(result) + "\n",
        f"**Tolerances, hand labels:** {lab_text}\n",
        f"**Tolerances, simulated scans:** {sim_text.removeprefix('tolerances: ')}\n",
        _headline_section(result),
        "## 1. Table 1 analogue: breakpoints and corners of 10 Intel frames\n",
        "The paper's Table 1 lists, for 10 Intel frames, the actual (hand-counted) and "
        "extracted numbers of breakpoints and corners of its method only, without saying "
        "which frames or where the events are. Here: the same counts for every method, and "
        "the matched precision and recall that counts alone cannot show.\n",
        f"### 1a. Hand-labelled Intel frames ({len(labelled.cases)})\n",
        f"{labelled.title}. Frames: scans "
        f"{', '.join(str(c.labels.scan) for c in labelled.cases if c.labels is not None)} of "
        "the excerpt; uncertain labels (events a careful reader could not decide) are listed "
        "separately.\n",
        *_label_details(result),
        _table1(labelled, lab_text, "uncertain"),
        f"### 1b. Simulated Intel-like scans ({len(t1.cases)}, lms_1deg)\n",
        f"{t1.title}; actual = every true event of the simulator; don't care = true events "
        "next to runs of fewer than "
        f"{tol.min_run} returns (matching one neither helps nor hurts).\n",
        _table1(t1, sim_text, "don't care"),
        "## 2. Table 3 analogue: counts, accuracy rate, matched scores and time\n",
        "The paper's Table 3 gives, for 10 TiM571 scans, the actual and found counts of IEPF "
        "and its method, the count-based accuracy rate and the time per scan.\n",
        f"### 2a. Simulated TiM571 scans ({len(t3.cases)}, the paper's sensor)\n",
        _table3_truth(t3, sim_text),
        "In the paper's layout (adaptive against IEPF per scan; ms: median over the repeats):\n",
        _table3_paper_layout(t3),
        f"### 2b. Hand-labelled Intel frames ({len(labelled.cases)})\n",
        _table3_truth(labelled, lab_text),
        "### 2c. Real excerpts without labels\n",
        "No truth: counts per scan, the similarity error (mean and RMS point-to-line "
        "distance over all points on segments) with the share of valid returns on segments, "
        "and time.\n",
    ]
    for run_ in result.real:
        parts += [f"**{run_.name}**: {len(run_.cases)} scans, {run_.title}.\n", _table3_real(run_)]
        note = _nonfinite_note(run_)
        if note:
            parts.append(note)
    parts += [_fig13_section(result, figures), _ground_truth_section(result, figures)]
    return "\n".join(parts)


def _label_details(result: ReproduceResult) -> list[str]:
    out = []
    if result.label_how_chosen:
        out.append(f"How the frames were chosen (from the label file): {result.label_how_chosen}\n")
    if result.label_rule:
        out.append(
            "<details><summary>The labelling rule (from the label file)</summary>\n\n"
            f"{result.label_rule}\n\n</details>\n"
        )
    return out
