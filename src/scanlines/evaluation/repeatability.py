"""Scan-to-scan repeatability on real logs, without labels: :func:`repeatability`.

A good extractor finds the same wall in the next scans of a log. The measure::

    from scanlines.evaluation.repeatability import repeatability

    result = repeatability("fr079.log.gz", ["adaptive", "iepf"], max_scans=300)
    result.table()                      # formatted rows, one per method spec
    write_results([result], "out/")     # repeatability.csv, repeatability_pairs.csv, .json

Pairs
-----
Scan ``i`` is paired with each scan ``j`` 1 to ``max_gap`` (3) records later (record
numbers of the log). Their relative pose (``j``'s sensor frame in ``i``'s) is refined by
the point-to-line ICP of :mod:`scanlines.geometry.registration`, starting from the
relative pose of the log's poses when both scans have one. A log without poses is
registered by ICP alone: ``(i, i + 1)`` from the identity and from the previous
consecutive estimate (constant velocity), keeping the fit with more inliers;
``(i, i + k)`` from the chain of the refined consecutive poses.

With ``max_pairs`` (``--pairs 200``) the candidate pairs, in log order, are cut into
``max_pairs`` slots of consecutive pairs, and each slot's pairs are registered in turn
(the gap cycling through 1 .. ``max_gap`` from slot to slot) until one is *used*: so
``max_pairs`` pairs are scored, spread evenly over the log, fewer only where a whole
slot has no usable pair. (Until 2026-12-04 ``max_pairs`` candidates were drawn and only
those of them that were used were scored: 59 of 200 on the Intel log, whose keyframes
turn 30 deg and more; see ``docs/decisions/strict-repeatability.md``.)

The *view overlap* of a pair is the smaller of two shares: of ``j``'s valid returns
that, moved into ``i``'s frame, fall inside ``i``'s field of view and range limits and
are not hidden behind ``i``'s own returns (farther than the largest range of the three
nearest beams of ``i`` plus ``occlusion_margin``), and the same of ``i``'s returns in
``j``. A pair is *used* when its view overlap is at least ``view_overlap`` (0.5) and its
registration has at least ``min_inliers`` (0.5) of ``j``'s returns within
``inlier_residual`` of ``i``'s local lines (see :class:`~.registration.Registration`).

Matching
--------
``j``'s segments are moved into ``i``'s frame with the refined pose. A segment ``s`` of
``i`` (start ``a``, unit direction ``u``, length ``L``) and a segment ``t`` of ``j``
match when all three hold:

* angle: the undirected angle between their directions is at most ``alpha`` (2 deg);
* overlap: project ``t``'s endpoints onto ``s``'s line, ``[lo, hi]`` along ``u`` from
  ``a``; ``overlap = |[lo, hi] & [0, L]| / min(L, hi - lo)`` is at least ``overlap``
  (0.5), the shorter length being ``t``'s projected length;
* distance: the point of ``t`` above the middle of that common interval is within
  ``distance`` (3 cm) of ``s``'s line (orthogonal distance; for straight segments it is
  the mean of the signed distances of the clipped endpoints: the Hesse-form offset at
  the place the two segments share, not at the origin). ``distance_at="origin"``
  compares ``|drho|`` of the two lines in Hesse form in ``i``'s frame instead (stricter
  for segments far from the foot of their normal; a sensitivity check).

Sensor profile (``mode``)
-------------------------
``"profiled"`` (the default): every method extracts with one sensor profile measured
from the log's first scans, as ``scanlines run`` does (or the one given: ``"given"``).
``"bare"``: each method gets one ``Extractor()`` with no profile, as ``extract(scan)``,
a bare :class:`~scanlines.Extractor` and the ROS 2 node without ``--sensor-profile`` use
it, fed the scans of the used pairs in log order (an extractor that learns from the
scans it has seen learns as it would on the log).

Scores (per method spec)
------------------------
* ``repeatability``: a *long* segment (``min_length``, 0.5 m) of a scan with at least
  one used pair counts as repeated when a segment of any of its used partner scans
  matches it; repeated long segments over long segments of scans with a used pair;
* ``per_pair``: the same counted per (long segment, used pair): matches over trials;
* ``coverage``: valid returns inside a segment's beam interval (outliers excluded) over
  valid returns, pooled over all scans;
* ``median_length`` of all segments with a line (metres; ``unfitted`` counts the
  segments whose line is NaN, which match nothing: the paper preset returns many on
  3-return runs); ``short_share``: segments fitted to fewer than ``few_points`` (5) returns
  over all segments; ``per_scan``: segments per scan;
* ``fidelity_mm``: in each direction of each used pair, every long segment of one scan
  with at least ``fidelity_returns`` (5) of the other scan's returns (moved into its
  frame by the refined pose) within its extent and within ``fidelity_band`` (10 cm) of
  its line gives the RMS distance of those returns to its line
  (:func:`~.repeat_scores.segment_fidelity`); the median over all of them, in mm. It
  holds the ICP's residual error as well as the segment's: compare methods on one log,
  not logs with each other;
* ``per_metre``: segments over *surface length*, the length of the polyline through
  consecutive valid returns (beam order) that both lie on segments, without the steps
  that cross a breakpoint the method reported (depth gaps); steps at corners count.
  Unlike segments over the summed segment length (1 / mean length), it does not fall
  when a method covers the surface with fewer, longer segments only by leaving returns
  out.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scanlines import Scan
from scanlines.evaluation.repeat_pairs import (
    OnProgress,
    PairRecord,
    RepeatTolerances,
    candidate_pairs,
    match_segments,
    register_pairs,
    view_overlap,
)
from scanlines.evaluation.repeat_scores import MethodRepeatability, _score_method
from scanlines.evaluation.specs import MethodSpec, parse_specs
from scanlines.geometry.registration import IcpSettings
from scanlines.report import jsonable, number, write_csv
from scanlines.sensor.profile import ProfileError, SensorProfile, estimate_profile

__all__ = [
    "TABLE_COLUMNS",
    "MethodRepeatability",
    "PairRecord",
    "RepeatTolerances",
    "RepeatabilityResult",
    "candidate_pairs",
    "match_segments",
    "register_pairs",
    "repeatability",
    "repeatability_of_scans",
    "view_overlap",
    "write_results",
]


# --------------------------------------------------------------------------- running


@dataclass(frozen=True, eq=False)
class RepeatabilityResult:
    """Pairs and per-method scores of one log.

    Attributes
    ----------
    log:
        The log's path as given.
    scans:
        Scans extracted (the first ``max_scans`` of the log, or all; with ``max_pairs``
        the scans of the used pairs).
    pose_source:
        ``"log poses + ICP"`` or ``"ICP alone"``.
    pairs:
        Every registered pair with its registration (:class:`PairRecord`).
    methods:
        One :class:`MethodRepeatability` per spec, in the order given.
    tol, icp:
        The tolerances and ICP settings used.
    mode:
        ``"profiled"`` (a profile measured from the log), ``"given"`` (the profile
        given) or ``"bare"`` (no profile); see :mod:`scanlines.evaluation.repeatability`.
    profile:
        The sensor profile every method extracted with (``None``: none).
    """

    log: str
    scans: int
    pose_source: str
    pairs: tuple[PairRecord, ...]
    methods: tuple[MethodRepeatability, ...]
    tol: RepeatTolerances
    icp: IcpSettings
    mode: str = "profiled"
    profile: SensorProfile | None = None

    @property
    def used_pairs(self) -> tuple[PairRecord, ...]:
        """The pairs that count."""
        return tuple(p for p in self.pairs if p.used)

    def pair_stats(self) -> dict[str, Any]:
        """Pair counts, and medians of motion and ICP quality over the used pairs."""
        used = self.used_pairs

        def median(values: list[float]) -> float:
            finite = [v for v in values if math.isfinite(v)]
            return float(np.median(finite)) if finite else math.nan

        return {
            "candidate_pairs": len(self.pairs),
            "used_pairs": len(used),
            "rejected_view": sum(p.view_overlap < self.tol.view_overlap for p in self.pairs),
            "rejected_icp": sum(
                p.view_overlap >= self.tol.view_overlap and p.inlier_fraction < self.tol.min_inliers
                for p in self.pairs
            ),
            "median_motion_m": median([p.motion[0] for p in used]),
            "median_turn_deg": median([math.degrees(p.motion[1]) for p in used]),
            "median_icp_correction_m": median([p.correction[0] for p in used]),
            "median_icp_correction_deg": median([math.degrees(p.correction[1]) for p in used]),
            "median_icp_rms_m": median([p.rms for p in used]),
            "median_icp_inliers": median([p.inlier_fraction for p in used]),
            "median_view_overlap": median([p.view_overlap for p in used]),
        }

    def summary_rows(self) -> list[dict[str, Any]]:
        """One row per method, with the log, pose source and used pairs."""
        head = {"log": self.log, "scans": self.scans, "pose_source": self.pose_source}
        head["mode"] = self.mode
        pairs = {"pairs_used": len(self.used_pairs)}
        return [head | m.to_dict() | pairs for m in self.methods]

    def pair_rows(self) -> list[dict[str, Any]]:
        """One row per candidate pair, with the log."""
        return [{"log": self.log} | p.to_dict() for p in self.pairs]

    def to_dict(self) -> dict[str, Any]:
        """Log, settings, pair statistics and the summary rows; NaN becomes ``None``."""
        return jsonable(
            {
                "log": self.log,
                "scans": self.scans,
                "pose_source": self.pose_source,
                "mode": self.mode,
                "profile": None if self.profile is None else self.profile.to_dict(),
                "tolerances": self.tol.to_dict(),
                "icp": self.icp.to_dict(),
                "pairs": self.pair_stats(),
                "methods": [m.spec.to_dict() for m in self.methods],
                "summary": self.summary_rows(),
            }
        )

    def title(self) -> str:
        """One line: the log, scans, pose source, mode and pairs."""
        stats = self.pair_stats()
        return (
            f"{self.log}: {self.scans} scans, {self.pose_source}, {self.noise()}, "
            f"{stats['used_pairs']} of "
            f"{stats['candidate_pairs']} pairs used ({stats['rejected_view']} view overlap, "
            f"{stats['rejected_icp']} ICP), median motion {number(stats['median_motion_m'])} "
            f"m / {number(stats['median_turn_deg'], '.1f')} deg, ICP rms "
            f"{number(100 * stats['median_icp_rms_m'], '.1f')} cm"
        )

    def noise(self) -> str:
        """The mode in words, with the profile's noise line."""
        if self.profile is None:
            return "bare: no profile" if self.mode == "bare" else f"{self.mode}: none measured"
        return (
            f"{self.mode}: {1000 * self.profile.noise_sigma0:.1f} mm + "
            f"{100 * self.profile.noise_per_metre:.2f} % of range"
        )

    def table(self) -> list[list[str]]:
        """Formatted :data:`TABLE_COLUMNS` rows, one per method."""
        return [
            [m.spec.label, *(number(fn(m), fmt) for _, fn, fmt in TABLE_COLUMNS)]
            for m in self.methods
        ]


TABLE_COLUMNS: tuple[tuple[str, Callable[[MethodRepeatability], float], str], ...] = (
    ("strict", lambda m: m.strict, ".3f"),
    ("repeated m/scan", lambda m: m.repeated_metres, ".2f"),
    ("repeat.", lambda m: m.repeatability, ".3f"),
    ("per pair", lambda m: m.per_pair, ".3f"),
    ("coverage", lambda m: m.coverage, ".3f"),
    ("fidelity mm", lambda m: m.fidelity_mm, ".1f"),
    ("median m", lambda m: m.median_length, ".2f"),
    ("< 5 returns", lambda m: m.short_share, ".3f"),
    ("seg/scan", lambda m: m.per_scan, ".1f"),
    ("seg/m", lambda m: m.per_metre, ".3f"),
    ("long", lambda m: m.long_segments, "d"),
)
"""Table columns: header, value of a :class:`MethodRepeatability`, format."""

TABLE_CAPTION = (
    "strict: each used pair scored on its own, both directions averaged, length-weighted, "
    "lines compared in Hesse form (|d rho| at the origin), only long segments the other scan "
    "observed; repeated m/scan: metres of long segments repeated per scan and direction; "
    "fidelity mm: median over long segments of the rms distance to their line of the other "
    "scan's returns within their extent and 10 cm of the line (at least 5); repeat.: long "
    "segments repeated in any used later pair / long segments; per pair: the same per "
    "(segment, pair); coverage: valid returns on segments; median m: median segment length; "
    "< 5 returns: share of segments; seg/m: segments per metre of surface (polyline through "
    "consecutive returns on segments, not across breakpoints); long: long segments of scans "
    "with a used pair."
)


def repeatability_of_scans(
    scans: Iterable[tuple[int, Scan]],
    specs: Iterable[str | MethodSpec],
    *,
    log: str = "",
    tol: RepeatTolerances | None = None,
    settings: IcpSettings | None = None,
    on_progress: OnProgress | None = None,
    sensor_profile: SensorProfile | None = None,
    bare: bool = False,
    registered: tuple[Sequence[PairRecord], str] | None = None,
) -> RepeatabilityResult:
    """Repeatability of ``specs`` on ``(record, scan)`` pairs in log order, every spec with
    ``sensor_profile`` (``None``: one measured from the scans, as ``scanlines run`` does);
    ``bare``: with no profile at all (one ``Extractor()`` per spec, fed the scans of the
    used pairs in log order). ``registered``: what :func:`register_pairs` gave for these
    scans, ``tol`` and ``settings`` (to score more specs or the other mode without
    registering the pairs again)."""
    parsed = parse_specs(specs)
    tol = tol or RepeatTolerances()
    settings = settings or IcpSettings()
    scans = list(scans)
    if bare and sensor_profile is not None:
        raise ValueError("bare mode extracts with no sensor profile; give none")
    mode = "bare" if bare else "profiled" if sensor_profile is None else "given"
    profile = None if bare else sensor_profile or _log_profile(scans, log)
    slots = len(candidate_pairs(scans, tol))
    if tol.max_pairs is not None:
        slots = min(slots, tol.max_pairs)
    total = slots + len(scans) * len(parsed)
    done = 0

    def tick(step: int = 1) -> None:
        nonlocal done
        done += step
        if on_progress is not None:
            on_progress(done, total)

    if registered is None:
        registered = register_pairs(scans, tol, settings, on_pair=lambda _d, _t: tick())
    else:
        tick(slots)
    pairs, source = tuple(registered[0]), registered[1]
    if tol.max_pairs is not None:  # only the scans of the used pairs are extracted
        used = {record for pair in pairs if pair.used for record in (pair.i, pair.j)}
        scans = [(record, scan) for record, scan in scans if record in used]
        total = done + len(scans) * len(parsed)
    methods = tuple(_score_method(spec, scans, pairs, tol, tick, profile) for spec in parsed)
    return RepeatabilityResult(
        log, len(scans), source, pairs, methods, tol, settings, mode, profile
    )


def _log_profile(scans: Sequence[tuple[int, Scan]], log: str) -> SensorProfile | None:
    """The profile ``scanlines run`` would measure; ``None`` (each scan its own) when the
    scans hold too few returns on surfaces."""
    try:
        return estimate_profile((scan for _, scan in scans), source=log)
    except ProfileError:
        return None


def repeatability(
    log_path: str | Path,
    specs: Iterable[str | MethodSpec],
    max_scans: int | slice | None = None,
    *,
    tol: RepeatTolerances | None = None,
    settings: IcpSettings | None = None,
    on_progress: OnProgress | None = None,
    sensor_profile: SensorProfile | None = None,
    bare: bool = False,
    **reader_options: Any,
) -> RepeatabilityResult:
    """Scan-to-scan repeatability of method specs on a log (any file ``open_log`` reads).

    Parameters
    ----------
    log_path:
        The log.
    specs:
        Method specs (:func:`~scanlines.evaluation.specs.parse_specs`); not ``truth``.
    max_scans:
        Read the first ``max_scans`` scans only (``None``: all), or those a slice of scan
        indices selects (``--scans``).
    tol, settings:
        :class:`RepeatTolerances` and :class:`~.registration.IcpSettings`.
    sensor_profile:
        The profile every spec extracts with; ``None``: measured from the scans read.
    bare:
        Extract with no profile at all (the *bare* mode); excludes ``sensor_profile``.
    on_progress:
        Called with ``(done, total)`` after each pair registered and each scan extracted.
    **reader_options:
        Options of the log's reader (:func:`scanlines.io.open_log`).
    """
    from scanlines.io import open_log
    from scanlines.reader_options import select_scans

    selection = max_scans if isinstance(max_scans, slice) else slice(max_scans)
    reader = open_log(log_path, **reader_options)
    scans = list(select_scans(reader.enumerate(), selection))
    return repeatability_of_scans(
        scans, specs, log=str(log_path), tol=tol, settings=settings, on_progress=on_progress,
        sensor_profile=sensor_profile, bare=bare,
    )  # fmt: skip


def write_results(results: Sequence[RepeatabilityResult], directory: str | Path) -> list[Path]:
    """Write ``repeatability.csv`` (one row per log and method), ``repeatability_pairs.csv``
    (one row per candidate pair) and ``repeatability.json`` into ``directory``."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    summary = [row for r in results for row in r.summary_rows()]
    pairs = [row for r in results for row in r.pair_rows()]
    out = [
        write_csv(directory / "repeatability.csv", summary),
        write_csv(directory / "repeatability_pairs.csv", pairs),
    ]
    path = directory / "repeatability.json"
    path.write_text(json.dumps([r.to_dict() for r in results], indent=2) + "\n")
    return [*out, path]
