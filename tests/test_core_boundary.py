"""Hostile arguments to every function of ``scanlines._core``: each is refused in one line.

Wrong lengths, positions outside their arrays, empty arrays, negative counts and windows,
NaN where a number is required, codes out of range: every call below must raise ValueError
or IndexError before the kernel reads or writes past an array. CI's sanitizer lane
(``.ci/sanitize``) runs this file under AddressSanitizer and UndefinedBehaviorSanitizer,
where a call that slipped through would be a report rather than a quiet wrong answer.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from scanlines import Extractor, _core

N = 12  # points of the scan every probe starts from: a wall with a corner
NAN = math.nan


def _points():
    index = np.arange(N, dtype=np.int64)
    x = np.where(index < 6, 2.0, 2.0 - 0.2 * (index - 5))
    y = np.where(index < 6, -1.0 + 0.2 * index, 0.0)
    return index, np.hypot(x, y), x, y


INDEX, R, X, Y = _points()
RETURNS = (INDEX, R, X, Y)
GAP = np.ones(N - 1, dtype=np.int64)
BREAKS = np.zeros(N - 1, dtype=bool)
FLAGS = np.zeros(N, dtype=bool)
TABLE, OX, OY = _core.prefix_moments(X, Y)
MOMENTS = (TABLE, OX, OY)
COST = (0, MOMENTS, np.zeros(0), np.zeros(0))
RULE = (1, 3.0, 0.0, 0.0, (0.01, 0.0), math.radians(10.0), 0.1, 0.3)  # ABD
SPEC = {
    "breakpoints": 1,
    "k": 3.0,
    "noise_k": 0.0,
    "line_k": 0.0,
    "abd_lambda": math.radians(10.0),
    "pdbs_c0": 0.1,
    "jump_distance": 0.3,
}
OUTPUT = {
    "min_points": 3,
    "min_length": 0.0,
    "range_sigma": NAN,
    "corner_beams": 2,
    "corner_distance": 0.5,
    "corner_angle": 0.5,
}
NOISE = (0.01, 0.0)
STEP = math.radians(1.0)
vec = np.array  # a literal int64 or float64 array
A2, B2, G2 = vec([0, 6]), vec([5, 11]), vec([0, 0])  # two runs of one cluster
START, END = vec([0]), vec([N - 1])  # one cluster
CANDIDATES, SCORES = vec([3, 5, 8]), vec([0.1, 0.9, 0.2])


def _ints(*values) -> np.ndarray:
    return np.array(values, dtype=np.int64)


def _sweep():
    return _core.start_sweep(COST, START, END, CANDIDATES, SCORES, np.zeros(0), False, 10)


def _edited(record: dict, group: str | None, **fields) -> dict:
    """``record`` with ``fields`` replaced (in ``group`` for a grouped record)."""
    out = {
        name: dict(values) if isinstance(values, dict) else values
        for name, values in record.items()
    }
    (out[group] if group else out).update(fields)
    return out


def _stack(name: str):
    """The arguments of method ``name``'s stack kernel on a stack of two scans, and its record."""
    method = Extractor(name)._method
    ranges = np.vstack([R, R[::-1]]).astype(np.float64)
    valid = np.ones_like(ranges, dtype=bool)
    angles = STEP * np.arange(N)
    sensor = (ranges, valid, np.cos(angles), np.sin(angles), STEP, False, -0.3, NOISE)
    return method.kernel, sensor, method.arguments


def _stack_probes(name: str, group: str, bad: dict) -> list[tuple[str, Callable]]:
    kernel, sensor, arguments = _stack(name)
    record, rest = arguments[0], arguments[1:]
    ranges, valid, cos, sin, step, full, angle_min, noise = sensor
    probes = [
        (
            "valid of another shape",
            lambda: kernel(
                ranges, valid[:, :-1], cos, sin, step, full, angle_min, noise, record, *rest
            ),
        ),
        (
            "cos too short",
            lambda: kernel(
                ranges, valid, cos[:-1], sin, step, full, angle_min, noise, record, *rest
            ),
        ),
        (
            "step NaN",
            lambda: kernel(ranges, valid, cos, sin, NAN, full, angle_min, noise, record, *rest),
        ),
        (
            "step 0",
            lambda: kernel(ranges, valid, cos, sin, 0.0, full, angle_min, noise, record, *rest),
        ),
        (
            "angle_min NaN",
            lambda: kernel(ranges, valid, cos, sin, step, full, NAN, noise, record, *rest),
        ),
        ("min_points -1", lambda: kernel(*sensor, _edited(record, "output", min_points=-1), *rest)),
    ]
    for field, value in bad.items():
        edited = _edited(record, group, **{field: value})
        probes.append((f"{field} {value}", lambda e=edited: kernel(*sensor, e, *rest)))
    return probes


def _filter(**changes):
    """filter_scan's arguments for one scan on a one-cell map of two lines, with ``changes``."""
    from scanlines.map.filter import FilterSettings

    args = {
        "state": np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
        "covariance": np.eye(7) * 0.01,
        "increment": np.zeros(3),
        "first": True,
        "x": X.copy(),
        "y": Y.copy(),
        "rho": vec([2.0, 0.0]),
        "normal": _core.line_normals(vec([0.0, math.pi / 2])),
        "start": vec([[2.0, -1.0], [2.0, 0.0]]),
        "end": vec([[2.0, 0.0], [0.0, 0.0]]),
        "sides": _ints(3, 3),
        "shape": vec([-10.0, -10.0, 20.0, 1.0, 1.0]),
        "cell_start": _ints(0, 2),
        "cell_lines": _ints(0, 1),
        "near_shape": vec([-10.0, -10.0, 20.0, 1.0, 1.0]),
        "near_cell_start": _ints(0, 2),
        "near_cell_lines": _ints(0, 1),
        "near_reach": 0.2,
        "settings": FilterSettings().record(),
        "max_points": 400,
    }
    args.update(changes)
    return lambda: _core.filter_scan(*args.values())


def _settings_with(group: str, name: str, value) -> dict:
    """The filter's settings record with one field changed."""
    from scanlines.map.filter import FilterSettings

    record = FilterSettings().record()
    record[group][name] = value
    return record


SHORT = GAP[:-1]  # a gap array one short

#: Binding name -> its hostile calls (label, call).
XY3, E3 = np.ones((3, 2)), np.zeros(3)  # point_to_line_system's lever, normals, residuals


def _point_to_line(lever=XY3, normals=XY3, residuals=E3, huber=1.0) -> Callable:
    return lambda: _core.point_to_line_system(lever, normals, residuals, huber)


PROBES: dict[str, list[tuple[str, Callable]]] = {
    "prefix_moments": [("y shorter", lambda: _core.prefix_moments(X, Y[:-1]))],
    "fit_many": [
        ("fit code 5", lambda: _core.fit_many(5, *MOMENTS, A2, B2)),
        ("b past the points", lambda: _core.fit_many(0, *MOMENTS, A2, vec([5, N]))),
        ("a negative", lambda: _core.fit_many(0, *MOMENTS, vec([-1, 6]), B2)),
        ("a and b of two lengths", lambda: _core.fit_many(0, *MOMENTS, A2, B2[:1])),
        ("a reversed run", lambda: _core.fit_many(0, *MOMENTS, vec([6]), vec([2]))),
        ("a table of 4 rows", lambda: _core.fit_many(0, TABLE[:4], OX, OY, A2, B2)),
        (
            "a table of no column",
            lambda: _core.fit_many(0, TABLE[:, :0], OX, OY, vec([0]), vec([-1])),
        ),
    ],
    "tls_run": [
        ("a negative", lambda: _core.tls_run(*MOMENTS, -1, 3)),
        ("b past the points", lambda: _core.tls_run(*MOMENTS, 0, N)),
        ("a reversed run", lambda: _core.tls_run(*MOMENTS, 8, 2)),
    ],
    "fit_run": [
        ("fit code -1", lambda: _core.fit_run(-1, *MOMENTS, 0, 5)),
        ("b past the points", lambda: _core.fit_run(1, *MOMENTS, 0, N)),
        ("a reversed run", lambda: _core.fit_run(1, *MOMENTS, 9, 1)),
    ],
    "run_covariances": [
        (
            "sigma too short",
            lambda: _core.run_covariances(
                R, X, Y, vec([2.0]), vec([0.0]), START, END, R[:-1], True
            ),
        ),
        (
            "rho for no run",
            lambda: _core.run_covariances(R, X, Y, vec([]), vec([0.0]), START, END, R, True),
        ),
        (
            "b past the points",
            lambda: _core.run_covariances(
                R, X, Y, vec([2.0]), vec([0.0]), START, vec([N]), R, True
            ),
        ),
        (
            "an empty run",
            lambda: _core.run_covariances(
                R, X, Y, vec([2.0]), vec([0.0]), vec([4]), vec([3]), R, True
            ),
        ),
    ],
    "pair_chi_squares": [
        (
            "first past the lines",
            lambda: _core.pair_chi_squares(
                vec([1.0, 2.0]), vec([0.0, 0.1]), np.zeros((2, 2, 2)), _ints(2), _ints(0)
            ),
        ),
        (
            "second negative",
            lambda: _core.pair_chi_squares(
                vec([1.0, 2.0]), vec([0.0, 0.1]), np.zeros((2, 2, 2)), _ints(0), _ints(-1)
            ),
        ),
        (
            "covariance for one line",
            lambda: _core.pair_chi_squares(
                vec([1.0, 2.0]), vec([0.0, 0.1]), np.zeros((1, 2, 2)), _ints(0), _ints(1)
            ),
        ),
        (
            "covariance 3 x 3",
            lambda: _core.pair_chi_squares(
                vec([1.0, 2.0]), vec([0.0, 0.1]), np.zeros((2, 3, 3)), _ints(0), _ints(1)
            ),
        ),
        (
            "second shorter",
            lambda: _core.pair_chi_squares(
                vec([1.0, 2.0]), vec([0.0, 0.1]), np.zeros((2, 2, 2)), _ints(0, 1), _ints(1)
            ),
        ),
    ],
    "covariance_sigmas": [
        ("gap too short", lambda: _core.covariance_sigmas(NAN, NOISE, *RETURNS, SHORT)),
        ("r too short", lambda: _core.covariance_sigmas(NAN, NOISE, INDEX, R[:-1], X, Y, GAP)),
    ],
    "local_residuals": [("gap empty", lambda: _core.local_residuals(*RETURNS, GAP[:0]))],
    "scan_noise": [("gap too long", lambda: _core.scan_noise(*RETURNS, np.ones(N, np.int64)))],
    "cluster_scan": [
        (
            "n_beams below the beams",
            lambda: _core.cluster_scan(*RETURNS, 5, STEP, False, SPEC, NOISE),
        ),
        ("n_beams 0", lambda: _core.cluster_scan(*RETURNS, 0, STEP, False, SPEC, NOISE)),
        ("step NaN", lambda: _core.cluster_scan(*RETURNS, N, NAN, False, SPEC, NOISE)),
        (
            "rule code 7",
            lambda: _core.cluster_scan(*RETURNS, N, STEP, False, {**SPEC, "breakpoints": 7}, NOISE),
        ),
        (
            "no return",
            lambda: _core.cluster_scan(*(v[:0] for v in RETURNS), N, STEP, True, SPEC, NOISE),
        ),
        (
            "beams out of order",
            lambda: _core.cluster_scan(INDEX[::-1].copy(), R, X, Y, N, STEP, False, SPEC, NOISE),
        ),
        (
            "a negative beam",
            lambda: _core.cluster_scan(INDEX - 1, R, X, Y, N, STEP, False, SPEC, NOISE),
        ),
    ],
    "finish": [
        (
            "group too short",
            lambda: _core.finish(
                *RETURNS,
                N,
                False,
                A2,
                B2,
                G2[:1],
                (True, False),
                _ints(5),
                _ints(),
                0.0,
                OUTPUT,
                NOISE,
            ),
        ),
        (
            "b past the points",
            lambda: _core.finish(
                *RETURNS,
                N,
                False,
                A2,
                vec([5, N]),
                G2,
                (True, False),
                _ints(5),
                _ints(),
                0.0,
                OUTPUT,
                NOISE,
            ),
        ),
        (
            "n_beams 0",
            lambda: _core.finish(
                *RETURNS,
                0,
                False,
                A2,
                B2,
                G2,
                (True, False),
                _ints(5),
                _ints(),
                0.0,
                OUTPUT,
                NOISE,
            ),
        ),
        (
            "min_points -1",
            lambda: _core.finish(
                *RETURNS,
                N,
                False,
                A2,
                B2,
                G2,
                (True, False),
                _ints(5),
                _ints(),
                0.0,
                {**OUTPUT, "min_points": -1},
                NOISE,
            ),
        ),
        (
            "corner_beams -3",
            lambda: _core.finish(
                *RETURNS,
                N,
                False,
                A2,
                B2,
                G2,
                (True, False),
                _ints(5),
                _ints(),
                0.0,
                {**OUTPUT, "corner_beams": -3},
                NOISE,
            ),
        ),
    ],
    "assemble": [
        (
            "sigma too short",
            lambda: _core.assemble(
                *RETURNS, 0, A2, B2, 0.0, R[:-1], _ints(), _ints(), _ints(), N, False
            ),
        ),
        (
            "fit code 9",
            lambda: _core.assemble(
                *RETURNS, 9, A2, B2, 0.0, R, _ints(), _ints(), _ints(), N, False
            ),
        ),
        (
            "a past the points",
            lambda: _core.assemble(
                *RETURNS,
                0,
                vec([N + 3]),
                vec([N + 4]),
                0.0,
                R,
                _ints(),
                _ints(),
                _ints(),
                N,
                False,
            ),
        ),
        (
            "an empty run",
            lambda: _core.assemble(
                *RETURNS, 0, vec([4]), vec([3]), 0.0, R, _ints(), _ints(), _ints(), N, False
            ),
        ),
    ],
    "offset_power_sums": [
        ("i outside the window", lambda: _core.offset_power_sums(INDEX, 0, 6, 9)),
        ("b past the index", lambda: _core.offset_power_sums(INDEX, 0, N, 3)),
    ],
    "parabola_at_centre": [
        ("r too short", lambda: _core.parabola_at_centre(INDEX, R[:5], 0, 6, 3, (7.0,) * 5)),
        ("a negative", lambda: _core.parabola_at_centre(INDEX, R, -2, 6, 3, (7.0,) * 5)),
    ],
    "threshold_grid": [
        ("max_evaluations -1", lambda: _core.threshold_grid(0.0, 1.0, 0.1, -1)),
        ("step 0", lambda: _core.threshold_grid(0.0, 1.0, 0.0, 10)),
        ("step NaN", lambda: _core.threshold_grid(0.0, 1.0, NAN, 10)),
        ("high NaN", lambda: _core.threshold_grid(0.0, NAN, 0.1, 10)),
    ],
    "start_sweep": [
        (
            "max_evaluations -1",
            lambda: _core.start_sweep(COST, START, END, CANDIDATES, SCORES, np.zeros(0), False, -1),
        ),
        (
            "a candidate past the points",
            lambda: _core.start_sweep(
                COST, START, END, _ints(3, N), vec([0.1, 0.2]), np.zeros(0), False, 10
            ),
        ),
        (
            "a candidate in no cluster",
            lambda: _core.start_sweep(
                COST, vec([4]), END, _ints(1), vec([0.5]), np.zeros(0), False, 10
            ),
        ),
        (
            "scores too short",
            lambda: _core.start_sweep(
                COST, START, END, CANDIDATES, SCORES[:1], np.zeros(0), False, 10
            ),
        ),
        (
            "clusters overlapping",
            lambda: _core.start_sweep(
                COST, _ints(0, 4), _ints(6, 11), CANDIDATES, SCORES, np.zeros(0), False, 10
            ),
        ),
        (
            "end past the points",
            lambda: _core.start_sweep(
                COST, START, _ints(N), CANDIDATES, SCORES, np.zeros(0), False, 10
            ),
        ),
        (
            "inv_r2 of another length",
            lambda: _core.start_sweep(
                (0, MOMENTS, np.zeros(3), np.zeros(3)),
                START,
                END,
                CANDIDATES,
                SCORES,
                np.zeros(0),
                False,
                10,
            ),
        ),
        (
            "fit code 4",
            lambda: _core.start_sweep(
                (4, MOMENTS, np.zeros(0), np.zeros(0)),
                START,
                END,
                CANDIDATES,
                SCORES,
                np.zeros(0),
                False,
                10,
            ),
        ),
    ],
    "extend_sweep": [
        ("upto past the candidates", lambda: _core.extend_sweep(_sweep(), COST, False, 0, 9)),
        ("done negative", lambda: _core.extend_sweep(_sweep(), COST, False, -1, 2)),
        ("upto before done", lambda: _core.extend_sweep(_sweep(), COST, False, 2, 1)),
        (
            "a cost of other points",
            lambda: _core.extend_sweep(
                _sweep(),
                (0, _core.prefix_moments(X[:5], Y[:5]), np.zeros(0), np.zeros(0)),
                False,
                0,
                3,
            ),
        ),
    ],
    "sweep_levels": [
        (
            "max_evaluations -1",
            lambda: _core.sweep_levels(
                COST, START, END, CANDIDATES, SCORES, np.zeros(0), False, -1, False
            ),
        ),
        (
            "a candidate past the points",
            lambda: _core.sweep_levels(
                COST, START, END, _ints(-4), vec([0.3]), np.zeros(0), False, 10, False
            ),
        ),
    ],
    "best_level": [
        (
            "a level past the cuts",
            lambda: _core.best_level(0, vec([1.0, 0.5]), _ints(1, 2), _ints(0, 2), N, 0.01, 4.0),
        ),
        (
            "segments too short",
            lambda: _core.best_level(0, vec([1.0, 0.5]), _ints(1), _ints(0, 1), N, 0.01, 4.0),
        ),
        (
            "criterion 5",
            lambda: _core.best_level(5, vec([1.0, 0.5]), _ints(1, 2), _ints(0, 1), N, 0.01, 4.0),
        ),
    ],
    "level_corners": [
        (
            "level past the candidates",
            lambda: _core.level_corners(_ints(3, 5), vec([True, True]), 3),
        ),
        ("level negative", lambda: _core.level_corners(_ints(3, 5), vec([True, True]), -1)),
        ("accepted too short", lambda: _core.level_corners(_ints(3, 5), vec([True]), 2)),
    ],
    "isolated_noise": [
        ("breaks too short", lambda: _core.isolated_noise(RETURNS, GAP, STEP, RULE, BREAKS[:2])),
        ("gap too short", lambda: _core.isolated_noise(RETURNS, SHORT, STEP, RULE, BREAKS)),
        ("a rule of 3 fields", lambda: _core.isolated_noise(RETURNS, GAP, STEP, RULE[:3], BREAKS)),
        ("rule kind 9", lambda: _core.isolated_noise(RETURNS, GAP, STEP, (9, *RULE[1:]), BREAKS)),
    ],
    "window_means": [
        ("window 0", lambda: _core.window_means(X, Y, FLAGS, 0, BREAKS)),
        ("noise too short", lambda: _core.window_means(X, Y, FLAGS[:3], 5, BREAKS)),
        ("breaks too short", lambda: _core.window_means(X, Y, FLAGS, 5, BREAKS[:0])),
        ("y too short", lambda: _core.window_means(X, Y[:4], FLAGS, 5, BREAKS)),
    ],
    "in_between_clusters": [
        ("small too short", lambda: _core.in_between_clusters(R, GAP, BREAKS, FLAGS[:1], 0.05)),
        ("breaks too short", lambda: _core.in_between_clusters(R, GAP, BREAKS[:1], FLAGS, 0.05)),
        ("gap too short", lambda: _core.in_between_clusters(R, SHORT, BREAKS, FLAGS, 0.05)),
    ],
    "denoise": [
        ("kind 7", lambda: _core.denoise(RETURNS, N, STEP, False, RULE, 7, 5, 2, 0.05)),
        ("window 0", lambda: _core.denoise(RETURNS, N, STEP, False, RULE, 1, 0, 2, 0.05)),
        (
            "min_cluster_points -2",
            lambda: _core.denoise(RETURNS, N, STEP, False, RULE, 0, 5, -2, 0.05),
        ),
        ("n_beams 0", lambda: _core.denoise(RETURNS, 0, STEP, False, RULE, 0, 5, 2, 0.05)),
        ("step NaN", lambda: _core.denoise(RETURNS, N, NAN, False, RULE, 0, 5, 2, 0.05)),
    ],
    "threshold": [
        ("rule kind 9", lambda: _core.threshold((9, *RULE[1:]), 2.0, 2.0, 1, STEP)),
        ("gap -1", lambda: _core.threshold(RULE, 2.0, 2.0, -1, STEP)),
        (
            "a noise of 3 terms",
            lambda: _core.threshold((*RULE[:4], (0.0, 0.0, 0.0), *RULE[5:]), 2.0, 2.0, 1, STEP),
        ),
    ],
    "break_flags": [
        ("gap too short", lambda: _core.break_flags(*RETURNS, SHORT, STEP, RULE)),
        ("gap empty", lambda: _core.break_flags(*RETURNS, GAP[:0], STEP, RULE)),
    ],
    "cluster_returns": [
        (
            "known_breaks too short",
            lambda: _core.cluster_returns(*RETURNS, N, STEP, False, RULE, 5, BREAKS[:3]),
        ),
        (
            "ring_window 0",
            lambda: _core.cluster_returns(*RETURNS, N, STEP, True, RULE, 0, BREAKS[:0]),
        ),
        (
            "n_beams below the beams",
            lambda: _core.cluster_returns(*RETURNS, 4, STEP, True, RULE, 5, BREAKS[:0]),
        ),
    ],
    "slope_scores": [
        (
            "start past the points",
            lambda: _core.slope_scores(R, GAP, STEP, _ints(N + 5), _ints(N + 6), False),
        ),
        ("end before start", lambda: _core.slope_scores(R, GAP, STEP, _ints(6), _ints(2), False)),
        ("gap too short", lambda: _core.slope_scores(R, SHORT, STEP, START, END, False)),
    ],
    "turn_scores": [
        ("end past the points", lambda: _core.turn_scores(X, Y, *MOMENTS, START, _ints(N), 5)),
        ("window 0", lambda: _core.turn_scores(X, Y, *MOMENTS, START, END, 0)),
        (
            "a table of other points",
            lambda: _core.turn_scores(X, Y, *_core.prefix_moments(X[:4], Y[:4]), START, END, 5),
        ),
    ],
    "peak_positions": [
        ("end past the scores", lambda: _core.peak_positions(R, START, _ints(N + 100))),
        ("start negative", lambda: _core.peak_positions(R, _ints(-50), END)),
        ("end shorter than start", lambda: _core.peak_positions(R, _ints(0, 6), _ints(5))),
    ],
    "chord_distance": [
        ("p past the points", lambda: _core.chord_distance(X, Y, 0, 5, N)),
        ("a negative", lambda: _core.chord_distance(X, Y, -1, 5, 2)),
        ("y too short", lambda: _core.chord_distance(X, Y[:3], 0, 5, 2)),
    ],
    "split_at_farthest": [
        (
            "b past the points",
            lambda: _core.split_at_farthest(X, Y, *MOMENTS, START, _ints(N), _ints(0), 0.1, 0),
        ),
        (
            "group too short",
            lambda: _core.split_at_farthest(X, Y, *MOMENTS, A2, B2, _ints(0), 0.1, 0),
        ),
        (
            "reference 4",
            lambda: _core.split_at_farthest(X, Y, *MOMENTS, START, END, _ints(0), 0.1, 4),
        ),
    ],
    "merge_by_chi_square": [
        (
            "sigma too short",
            lambda: _core.merge_by_chi_square(*RETURNS, *MOMENTS, A2, B2, G2, R[:2], 9.21, True),
        ),
        (
            "a reversed run",
            lambda: _core.merge_by_chi_square(
                *RETURNS, *MOMENTS, _ints(6, 0), _ints(5, 11), G2, R, 9.21, True
            ),
        ),
        (
            "a table of other points",
            lambda: _core.merge_by_chi_square(
                *RETURNS, *_core.prefix_moments(X[:3], Y[:3]), A2, B2, G2, R, 9.21, True
            ),
        ),
    ],
    "segment_events": [
        (
            "group too short",
            lambda: _core.segment_events(
                *RETURNS, N, *MOMENTS, A2, B2, G2[:1], True, False, 2, 0.5, 0.5
            ),
        ),
        (
            "b past the points",
            lambda: _core.segment_events(
                *RETURNS, N, *MOMENTS, A2, _ints(5, N + 1), G2, True, False, 2, 0.5, 0.5
            ),
        ),
        (
            "corner_beams -1",
            lambda: _core.segment_events(
                *RETURNS, N, *MOMENTS, A2, B2, G2, True, False, -1, 0.5, 0.5
            ),
        ),
        (
            "n_beams 0",
            lambda: _core.segment_events(
                *RETURNS, 0, *MOMENTS, A2, B2, G2, True, False, 2, 0.5, 0.5
            ),
        ),
    ],
    "junction_events": [
        (
            "turn_sigma too short",
            lambda: _core.junction_events(
                *RETURNS, 0, *MOMENTS, A2, B2, G2, False, False, 0.01, vec([0.1])
            ),
        ),
        (
            "owner too short",
            lambda: _core.junction_events(
                *RETURNS, 0, *MOMENTS, A2, B2, G2[:1], False, False, 0.01, np.zeros(0)
            ),
        ),
        (
            "fit code 3",
            lambda: _core.junction_events(
                *RETURNS, 3, *MOMENTS, A2, B2, G2, False, False, 0.01, np.zeros(0)
            ),
        ),
        (
            "a past the points",
            lambda: _core.junction_events(
                *RETURNS, 0, *MOMENTS, _ints(0, 40), B2, G2, True, True, 0.01, np.zeros(0)
            ),
        ),
    ],
    "sweep_decided": [
        (
            "done past the candidates",
            lambda: _core.sweep_decided(_sweep(), COST, False, 9, N, 0.01, 4.0),
        ),
        ("done negative", lambda: _core.sweep_decided(_sweep(), COST, False, -1, N, 0.01, 4.0)),
        (
            "a cost of other points",
            lambda: _core.sweep_decided(
                _sweep(),
                (0, _core.prefix_moments(X[:5], Y[:5]), np.zeros(0), np.zeros(0)),
                False,
                0,
                N,
                0.01,
                4.0,
            ),
        ),
    ],
    "partition_optimal_runs": [
        (
            "opens too short",
            lambda: _core.partition_optimal_runs(X, Y, R, 0.01, FLAGS[:2], 4.0, 1.0, 3),
        ),
        ("min_points -1", lambda: _core.partition_optimal_runs(X, Y, R, 0.01, FLAGS, 4.0, 1.0, -1)),
    ],
    "adaptive_stack": _stack_probes(
        "adaptive",
        "segments",
        {
            "max_evaluations": -1,
            "slope_window": -2,
            "criterion": 2,
            "fit": 7,
            "corner_score": 3,
        },
    )
    + _stack_probes(
        "adaptive",
        "clustering",
        {"window": 0, "denoise": 5, "min_cluster_points": -1, "breakpoints": 4},
    ),
    "adaptive_stage_seconds": [
        (
            "max_evaluations -1",
            lambda: _core.adaptive_stage_seconds(
                *_stack("adaptive")[1],
                _edited(_stack("adaptive")[2][0], "segments", max_evaluations=-1),
                _stack("adaptive")[2][1],
            ),
        ),
        (
            "cos too short",
            lambda: _core.adaptive_stage_seconds(
                *_stack("adaptive")[1][:2],
                _stack("adaptive")[1][2][:3],
                *_stack("adaptive")[1][3:],
                *_stack("adaptive")[2],
            ),
        ),
    ],
    "paper_stack": _stack_probes("paper", "clustering", {"window": 0}),
    "partition_stack": _stack_probes("partition", "output", {"min_points": -4}),
    "surfaces_stack": _stack_probes("surfaces", "output", {"min_points": -4}),
    "iepf_stack": _stack_probes("iepf", "segments", {"split_reference": 5}),
    "split_merge_stack": _stack_probes("split_merge", "clustering", {"breakpoints": -2, "k": NAN}),
    "filter_scan": [
        ("a count setting 0", _filter(settings=_settings_with("solver", "iterations", 0))),
        (
            "a count setting negative",
            _filter(settings=_settings_with("association", "line_returns", -3)),
        ),
        ("a count setting 1e300", _filter(settings=_settings_with("solver", "min_pairs", 10**300))),
        ("a number setting NaN", _filter(settings=_settings_with("noise", "huber", NAN))),
        ("nx NaN", _filter(shape=vec([-10.0, -10.0, 20.0, NAN, 1.0]))),
        ("nx 1e300", _filter(shape=vec([-10.0, -10.0, 20.0, 1e300, 1.0]))),
        ("cell 0", _filter(shape=vec([-10.0, -10.0, 0.0, 1.0, 1.0]))),
        ("x0 NaN", _filter(shape=vec([NAN, -10.0, 20.0, 1.0, 1.0]))),
        ("cell starts of 2 x 1 cells", _filter(cell_start=_ints(0, 1, 2))),
        ("cell starts past the ids", _filter(cell_start=_ints(0, 5))),
        ("near nx NaN", _filter(near_shape=vec([-10.0, -10.0, 20.0, NAN, 1.0]))),
        ("near cell NaN", _filter(near_shape=vec([-10.0, -10.0, NAN, 1.0, 1.0]))),
        ("near cell starts of 2 x 1 cells", _filter(near_cell_start=_ints(0, 1, 2))),
        ("near cell starts past the ids", _filter(near_cell_start=_ints(0, 5))),
        ("near_reach NaN", _filter(near_reach=NAN)),
        ("near_reach -1", _filter(near_reach=-1.0)),
        ("max_points -1", _filter(max_points=-1)),
        ("normal too short", _filter(normal=_core.line_normals(vec([0.0])))),
        ("normal of 1 column", _filter(normal=vec([[1.0], [0.0]]))),
        ("sides too short", _filter(sides=_ints(3))),
        ("y too short", _filter(y=Y[:3].copy())),
        ("a covariance 6 x 6", _filter(covariance=np.eye(6))),
        ("an increment of 2", _filter(first=False, increment=np.zeros(2))),
    ],
    "point_to_line_system": [
        ("lever shorter", _point_to_line(lever=np.zeros((2, 2)))),
        ("normals K x 3", _point_to_line(normals=np.zeros((3, 3)))),
        ("residuals longer", _point_to_line(residuals=vec([0.0] * 4))),
        ("huber NaN", _point_to_line(huber=NAN)),
        ("huber negative", _point_to_line(huber=-1.0)),
    ],
}

if not hasattr(_core, "adaptive_stage_seconds"):  # bound only in the stage-times build
    del PROBES["adaptive_stage_seconds"]

CASES = [(name, label, call) for name, calls in PROBES.items() for label, call in calls]

# Functions of plain numbers or of one array they only read in order: nothing to index out of
# range. A NaN, an empty array or an extreme number must still come back as a result.
NUMBERS: dict[str, Callable] = {
    "hesse_difference": lambda: _core.hesse_difference(NAN, 0.0, 1.0, NAN),
    "auto_abd_lambda": lambda: _core.auto_abd_lambda(NAN),
    "residual_tolerances": lambda: _core.residual_tolerances(vec([NAN, -1.0, 1e308]), NOISE, NAN),
    "literal_noise": lambda: _core.literal_noise(np.zeros(0)),
    "read_fields": lambda: _core.read_fields(b"\x00\xff 1e999999 -" + b"9" * 5000),
    "line_normals": lambda: _core.line_normals(vec([NAN, -1e308, 1e308, 0.0])),
}
# Values the kernels skip by design (documented at their binding): no error, a result.
SKIPPED: dict[str, Callable] = {
    "filter_scan": _filter(cell_lines=_ints(0, 99)),  # a line id past the lines: ignored
    "filter_scan near": _filter(near_cell_lines=_ints(-1, 99)),  # the same in the near grid
}


def test_every_function_of_the_core_has_probes():
    functions = {
        name
        for name in dir(_core)
        if not name.startswith("_") and callable(getattr(_core, name)) and name != "Sweep"
    }
    assert functions == set(PROBES) | set(NUMBERS)


@pytest.mark.parametrize(("name", "label", "call"), CASES, ids=[f"{n}: {x}" for n, x, _ in CASES])
def test_a_hostile_call_is_refused_in_one_line(name, label, call):
    with pytest.raises((ValueError, IndexError)) as refused:
        call()
    message = str(refused.value)
    assert message, (name, label)
    assert "\n" not in message, (name, label, message)


@pytest.mark.parametrize("name", sorted(NUMBERS))
def test_a_function_of_numbers_returns_on_nan_and_extremes(name):
    NUMBERS[name]()


def test_the_filter_skips_a_line_id_past_the_lines():
    assert SKIPPED["filter_scan"]()[6] in range(8)
    assert SKIPPED["filter_scan near"]()[6] in range(8)


@pytest.mark.parametrize(
    "call",
    [
        lambda: _core.fit_many(0, *MOMENTS, A2, B2),
        lambda: _core.finish(
            *RETURNS, N, False, A2, B2, G2, (True, False), _ints(5), _ints(), 0.0, OUTPUT, NOISE
        ),
        lambda: _core.sweep_levels(
            COST, START, END, CANDIDATES, SCORES, np.zeros(0), False, 10, False
        ),
        lambda: _core.extend_sweep(_sweep(), COST, False, 0, 3),
        lambda: _core.segment_events(*RETURNS, N, *MOMENTS, A2, B2, G2, True, False, 2, 0.5, 0.5),
        _filter(),
        *[
            lambda n=n: (lambda k, s, a: k(*s, *a))(*_stack(n))
            for n in ("adaptive", "paper", "partition", "surfaces", "iepf", "split_merge")
        ],
    ],
)
def test_the_probes_start_from_calls_that_succeed(call):
    """Each probe changes one argument of a call like these, which the kernels accept."""
    call()


def test_a_settings_record_takes_plain_python_numbers_only():
    kernel, sensor, (record,) = _stack("partition")
    with pytest.raises(TypeError, match=r"min_points must be an int, got numpy\.int64"):
        kernel(*sensor, _edited(record, "output", min_points=np.int64(3)))
    with pytest.raises(TypeError, match="must be an int, got float"):
        kernel(*sensor, _edited(record, "output", min_points=3.0))
    with pytest.raises(ValueError, match="out of range"):
        kernel(*sensor, _edited(record, "output", min_points=2**70))
