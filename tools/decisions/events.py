"""Where the default method's breakpoint and corner errors come from, and what a scan can decide.

    python tools/decisions/events.py            # 300 scenes per sensor, seed 0
    python tools/decisions/events.py -n 20 --seed 1

Two tables per sensor preset, on the scenes, seeds and tolerances of ``scanlines eval``:

1. **What one scan cannot decide.** A true breakpoint between two line surfaces, with at
   most one missing beam between its two returns, whose two lines meet at a bearing
   strictly between the two beams: a world where the surfaces meet there (a corner) gives
   the same returns, so no method can tell the two apart from the scan (a mixed pixel
   between them is the only hint; it is counted). Were every such breakpoint called a
   corner by an otherwise perfect method, its F1 scores would be the bounds printed.
2. **The default adaptive method's counted errors**, each in one class: a false
   breakpoint at a true corner (the corner was cut), a second report of a true breakpoint
   that another found breakpoint matched, one within three beams of an outlier or mixed
   pixel, or one on a plain surface; a missed true event reported as the other kind, or
   missed; a missed corner by the returns on its shorter side.

The matching is the metric's own (:func:`scanlines.evaluation.metrics.match_events`), and
the counts are checked against :func:`scanlines.evaluation.metrics.score`.
"""

from __future__ import annotations

import argparse
import math
from collections import Counter

import numpy as np

from scanlines import Extraction, Extractor, Scan
from scanlines.evaluation.metrics import event_dont_care, match_events, score
from scanlines.evaluation.scenes import iter_scenes
from scanlines.evaluation.scores import Tolerances
from scanlines.sim import SENSORS
from scanlines.truth import BeamStatus, Truth

NEAR_NOISE_BEAMS = 3
"""A false event this close to an outlier or mixed pixel is put in that class."""


# --------------------------------------------------------------------------- observability


def undecidable_breakpoints(truth: Truth, scan: Scan, tol: Tolerances) -> tuple[int, int]:
    """Counted true breakpoints that look exactly like a corner, and those of them with a mixed pixel."""
    returns = np.flatnonzero(truth.true_return)
    counted = ~event_dont_care(truth.breakpoint_runs, tol.min_run)
    angles = scan.angles
    undecidable = with_mixed = 0
    for beam in truth.breakpoints[counted]:
        position = np.searchsorted(returns, beam)
        if position + 1 >= returns.shape[0]:
            continue
        after = int(returns[position + 1])
        if after - beam > 2 or truth.on_curve[beam] or truth.on_curve[after]:
            continue
        meet = _lines_meet(truth, int(beam), after)
        if meet is None:
            continue
        bearing = math.atan2(meet[1], meet[0])
        if (bearing - angles[beam]) * (bearing - angles[after]) < 0.0:
            undecidable += 1
            with_mixed += bool(np.any(truth.status[beam + 1 : after] == BeamStatus.MIXED))
    return undecidable, with_mixed


def _lines_meet(truth: Truth, before: int, after: int) -> np.ndarray | None:
    """Where the true lines of the surfaces hit by beams ``before`` and ``after`` meet."""
    first, second = _edge_line(truth, before), _edge_line(truth, after)
    if first is None or second is None:
        return None
    (p, u), (q, v) = first, second
    cross = u[0] * v[1] - u[1] * v[0]
    if abs(cross) < 1e-12:  # parallel surfaces never meet
        return None
    s = ((q[0] - p[0]) * v[1] - (q[1] - p[1]) * v[0]) / cross
    return p + s * u


def _edge_line(truth: Truth, beam: int) -> tuple[np.ndarray, np.ndarray] | None:
    """A point and direction of the edge ``beam`` hits, from two exact hits on it."""
    for other in (beam - 1, beam + 1, beam - 2, beam + 2):
        if 0 <= other < truth.n_beams and truth.edge[other] == truth.edge[beam]:
            return truth.hit_points[beam], truth.hit_points[other] - truth.hit_points[beam]
    return None


# --------------------------------------------------------------------------- error classes


def error_classes(found: Extraction, truth: Truth, tol: Tolerances) -> Counter:
    """Counted false and missed events of ``found``, each in one class."""
    out: Counter = Counter()
    near_noise = _near(truth, (BeamStatus.OUTLIER, BeamStatus.MIXED), NEAR_NOISE_BEAMS)
    events = (
        ("breakpoint", found.breakpoints, truth.breakpoints, truth.breakpoint_runs),
        ("corner", found.corners, truth.corners, truth.corner_runs),
    )
    for kind, found_at, true_at, runs in events:
        other = "corner" if kind == "breakpoint" else "breakpoint"
        true_other = truth.corners if kind == "breakpoint" else truth.breakpoints
        found_other = found.corners if kind == "breakpoint" else found.breakpoints
        f_pos, t_pos = match_events(
            found_at, true_at, tol.event_beams, n_beams=truth.n_beams, circular=truth.full_circle
        )
        f_matched = np.isin(np.arange(found_at.shape[0]), f_pos)
        t_matched = np.isin(np.arange(true_at.shape[0]), t_pos)
        for beam in found_at[~f_matched]:
            if tol.curved_dont_care and truth.on_curve[beam]:
                continue
            if _within(beam, true_other, tol.event_beams):
                label = f"at a true {other}"
            elif _within(beam, true_at, tol.event_beams):
                label = f"second report of a true {kind}"
            elif near_noise[beam]:
                label = "near an outlier or mixed pixel"
            else:
                label = "on a plain surface"
            out[f"false {kind}: {label}"] += 1
        dont_care = event_dont_care(runs, tol.min_run)
        for j in np.flatnonzero(~t_matched & ~dont_care):
            if _within(true_at[j], found_other, tol.event_beams):
                label = f"reported as a {other}"
            elif kind == "corner":
                shorter = int(np.min(runs[j]))
                label = f"missed, shorter side {'3-7' if shorter < 8 else '8+'} returns"
            else:
                label = "missed"
            out[f"missed {kind}: {label}"] += 1
    return out


def _within(beam: int, beams: np.ndarray, tolerance: int) -> bool:
    return bool(beams.shape[0]) and bool(np.min(np.abs(beams - beam)) <= tolerance)


def _near(truth: Truth, statuses: tuple[BeamStatus, ...], reach: int) -> np.ndarray:
    """Beams within ``reach`` of a beam with one of ``statuses``."""
    marked = np.flatnonzero(np.isin(truth.status, statuses))
    near = np.zeros(truth.n_beams, dtype=bool)
    for beam in marked:
        near[max(beam - reach, 0) : beam + reach + 1] = True
    return near


# --------------------------------------------------------------------------- report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=300, help="scenes per sensor")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    tol, extractor = Tolerances(), Extractor("adaptive")
    counts = {sensor: Counter() for sensor in SENSORS}
    errors = {sensor: Counter() for sensor in SENSORS}
    for sensor in SENSORS:
        for case in iter_scenes([sensor], args.n, args.seed):
            scan, truth = case.scan, case.truth
            found = extractor(scan)
            scores = score(found, truth, scan, tol)
            classes = error_classes(found, truth, tol)
            _check(classes, scores, sensor, case.index)
            errors[sensor] += classes
            undecidable, with_mixed = undecidable_breakpoints(truth, scan, tol)
            counts[sensor].update(
                breakpoints=scores.breakpoints.tp + scores.breakpoints.fn,
                corners=scores.corners.tp + scores.corners.fn,
                undecidable=undecidable,
                with_mixed=with_mixed,
            )

    print(f"{args.n} scenes per sensor, seed {args.seed}, default tolerances.\n")
    print("True breakpoints that one scan cannot tell from a corner:\n")
    _row("sensor", "counted breakpoints", "counted corners", "undecidable", "of them with a "
         "mixed pixel", "corner F1 bound", "breakpoint F1 bound")  # fmt: skip
    _row(*["---"] * 7)
    for sensor, c in counts.items():
        b, k, a = c["breakpoints"], c["corners"], c["undecidable"]
        _row(sensor, b, k, a, c["with_mixed"], f"{2 * k / (2 * k + a):.3f}",
             f"{2 * (b - a) / (2 * b - a):.3f}")  # fmt: skip

    print("\nThe default adaptive method's counted errors, by class:\n")
    labels = sorted({label for c in errors.values() for label in c})
    _row("class", *SENSORS)
    _row(*["---"] * (1 + len(SENSORS)))
    for label in labels:
        _row(label, *(errors[sensor][label] for sensor in SENSORS))


def _check(classes: Counter, scores, sensor: str, index: int) -> None:
    """The classes add up to the metric's own false and missed counts."""
    for kind, event in (("breakpoint", scores.breakpoints), ("corner", scores.corners)):
        fp = sum(v for k, v in classes.items() if k.startswith(f"false {kind}"))
        fn = sum(v for k, v in classes.items() if k.startswith(f"missed {kind}"))
        if (fp, fn) != (event.fp, event.fn):
            raise AssertionError(f"{sensor} #{index}: {kind} counts differ from score()")


def _row(*cells: object) -> None:
    print("| " + " | ".join(str(c) for c in cells) + " |")


if __name__ == "__main__":
    main()
