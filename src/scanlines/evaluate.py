"""Benchmark extractors on simulated scans with exact ground truth.

Run one or more *method specs* on the same generated scenes of every sensor preset,
score each extraction with :func:`scanlines.metrics.score` and pool the scores per
sensor and method::

    from scanlines.evaluate import evaluate

    result = evaluate(["adaptive", "adaptive:paper"], sensors=["tim571"], n=20)
    result.to_csv("out/")              # per_scan.csv, summary.csv
    result.to_json("out/summary.json")

Method specs
------------
A spec names a method, optionally a preset, parameter overrides and a label::

    METHOD[:PRESET][?NAME=VALUE[&NAME=VALUE]...][@LABEL]

``adaptive``, ``adaptive:paper``, ``adaptive?k=4&fit=paper``,
``adaptive:paper?k=4@paper-k4``. Values are validated by the method (a pair is
written ``dkth_range=0,0.05``). The label defaults to the spec text without the
label; labels must be unique within a run.

The truth row
-------------
The spec ``truth`` (optionally ``truth@LABEL``; no preset or parameters) is not a
method but a reference row (an oracle), built from each scene's truth by
:func:`truth_extraction`: the true segments' beam runs, each fitted by total least
squares to the scan's measured returns the truth says hit that segment's edge, with
the true breakpoints and corners. It is scored like every method, with the same
tolerances: the best any segmentation can do with exact boundaries, the ceiling of
the segment metrics (its breakpoint and corner F1 are 1 by construction). It needs
the truth, so it is not an extraction method and not in :func:`scanlines.methods`.

Scenes and seeds
----------------
Scene ``i`` of sensor ``s`` is ``random_scene(seed_i, s).scan(seed_i)`` with
``seed_i = scene_seed(seed, s, i)``: a 32-bit integer from
``numpy.random.SeedSequence([seed, crc32(s), i])``. Every spec sees the same scans,
and the same arguments give the same numbers on every run. Noise is the preset's
realistic model (``"realistic"``) or none (``"exact"``, ``NoiseModel()``).

Scene sets
----------
:func:`save_scene_set` writes a compressed ``.npz`` holding, for every scene, the
recipe (sensor, index, seed, kind, noise) *and* the generated data: the scan
(ranges, beam layout, range limits, pose) and every array of its
:class:`~scanlines.sim.truth.Truth`. :func:`load_scene_set` rebuilds the scans and
truths from the arrays alone, so a saved set stays fixed when the simulator
changes. The world geometry is not stored (scoring and plots do not need it).

Timing
------
``us`` is the wall time of the extraction call alone (``time.perf_counter_ns``), in
microseconds; summaries report its median (and mean) per sensor and spec. With
``workers > 1`` the processes share the machine, so times are less comparable. For
the truth row it is the time of building the row from the truth.
"""

from __future__ import annotations

import csv
import json
import math
import time
import zlib
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields
from functools import lru_cache, partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from scanlines.errors import LogFormatError, ParameterError
from scanlines.extractor import Extractor
from scanlines.metrics import ScanScore, Summary, Tolerances, aggregate, score
from scanlines.scan import Scan
from scanlines.sim.noise import NoiseModel
from scanlines.sim.scenes import random_scene
from scanlines.sim.sensors import SENSORS, get_sensor
from scanlines.sim.truth import TrueSegments, Truth
from scanlines.steps.assemble import assemble, to_extraction
from scanlines.steps.fit import TLS, prefix_moments, run_labels
from scanlines.steps.returns import Returns

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from scanlines.extraction import Extraction

__all__ = [
    "ALL_SENSORS",
    "DEFAULT_SCENES",
    "NOISES",
    "TABLE_COLUMNS",
    "TRUTH",
    "EvalConfig",
    "EvalResult",
    "MethodSpec",
    "ScanRecord",
    "SceneCase",
    "SceneSet",
    "SummaryRecord",
    "WorstScan",
    "evaluate",
    "event_f1",
    "generate_scene_set",
    "iter_scenes",
    "load_scene_set",
    "make_scene",
    "parse_spec",
    "parse_specs",
    "plot_bars",
    "plot_truth_overlay",
    "plot_worst",
    "save_scene_set",
    "scene_seed",
    "tolerance_caption",
    "truth_extraction",
    "worst_scans",
]

NOISES = ("realistic", "exact")
"""Noise choices: the sensor preset's own model, or exact ranges."""

DEFAULT_SCENES = 100
"""Scenes per sensor when generating and none is given."""

ALL_SENSORS = "all"
"""The ``sensor`` of summary rows pooled over every sensor."""

WORST_BY = (
    "event F1: 2 TP / (2 TP + FP + FN) with breakpoints and corners pooled "
    "(1 when the scan has nothing counted), mean over the specs; lowest first"
)
"""How :func:`worst_scans` ranks scans."""

TRUTH = "truth"
"""Spec name of the truth row (see :func:`truth_extraction`); not a method."""

SCENE_SET_FORMAT = "scanlines-scene-set"
SCENE_SET_VERSION = 1

OnScene = Callable[[int, int], None]


# --------------------------------------------------------------------------- specs


@dataclass(frozen=True)
class MethodSpec:
    """One configuration of one method, and its label in the results.

    Attributes
    ----------
    method:
        A name from :func:`scanlines.methods`, or :data:`TRUTH` for the truth row.
    preset:
        A preset of the method, or ``None``.
    params:
        ``(name, value)`` overrides in the order given (values as written).
    label:
        Name of this configuration in tables, files and figures; the spec text
        (:attr:`text`) when empty.
    """

    method: str
    preset: str | None = None
    params: tuple[tuple[str, Any], ...] = ()
    label: str = ""

    def __post_init__(self) -> None:
        if not self.label:
            object.__setattr__(self, "label", self.text)

    @property
    def text(self) -> str:
        """The spec without its label: ``METHOD[:PRESET][?NAME=VALUE&...]``."""
        preset = f":{self.preset}" if self.preset else ""
        query = "&".join(f"{k}={v}" for k, v in self.params)
        return f"{self.method}{preset}{'?' + query if query else ''}"

    @property
    def params_text(self) -> str:
        """The overrides as ``NAME=VALUE&...`` (empty without overrides)."""
        return "&".join(f"{k}={v}" for k, v in self.params)

    @property
    def is_truth(self) -> bool:
        """Whether this is the truth row (:data:`TRUTH`), not a method."""
        return self.method == TRUTH

    def extractor(self) -> Extractor:
        """The configured :class:`~scanlines.Extractor` (validates the spec).

        Raises
        ------
        ParameterError
            For the truth row, which has no extractor (it needs the truth).
        """
        if self.is_truth:
            raise ParameterError(f"{TRUTH!r} is built from the truth and has no extractor")
        return Extractor(self.method, self.preset, **dict(self.params))

    def to_dict(self) -> dict[str, Any]:
        """Label, method, preset, overrides and the full resolved parameters."""
        return {
            "label": self.label,
            "spec": self.text,
            "method": self.method,
            "preset": self.preset,
            "params": dict(self.params),
            "resolved": {}
            if self.is_truth
            else {k: _jsonable(v) for k, v in self.extractor().params.items()},
        }


def parse_spec(text: str) -> MethodSpec:
    """Parse ``METHOD[:PRESET][?NAME=VALUE[&NAME=VALUE]...][@LABEL]`` and validate it.

    Raises
    ------
    ParameterError
        For bad syntax, or an unknown method, preset or parameter, or a bad value
        (the message starts with the spec).
    """
    try:
        spec = _split_spec(text.strip())
        _check_spec(spec)
    except ParameterError as error:
        raise ParameterError(f"method spec {text!r}: {error}") from None
    return spec


def _split_spec(text: str) -> MethodSpec:
    body, at, label = text.partition("@")
    if at and not label.strip():
        raise ParameterError("empty label after '@'")
    head, question, query = body.partition("?")
    method, colon, preset = head.partition(":")
    if not method.strip():
        raise ParameterError("no method name")
    if colon and not preset.strip():
        raise ParameterError("empty preset after ':'")
    if question and not query.strip():
        raise ParameterError("no NAME=VALUE after '?'")
    params = _split_query(query) if question else ()
    return MethodSpec(method.strip(), preset.strip() or None, params, label.strip())


def _split_query(query: str) -> tuple[tuple[str, str], ...]:
    pairs: list[tuple[str, str]] = []
    for part in query.split("&"):
        name, eq, value = part.partition("=")
        if not eq or not name.strip() or not value.strip():
            raise ParameterError(f"parameters are NAME=VALUE joined by '&', got {part!r}")
        pairs.append((name.strip(), value.strip()))
    names = [name for name, _ in pairs]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise ParameterError(f"parameter(s) given twice: {', '.join(repeated)}")
    return tuple(pairs)


def parse_specs(specs: Iterable[str | MethodSpec]) -> tuple[MethodSpec, ...]:
    """Parse (and validate) several specs; labels must be unique.

    Raises
    ------
    ParameterError
        For a bad spec, no spec at all, or a label used twice.
    """
    parsed = tuple(_validated(s) if isinstance(s, MethodSpec) else parse_spec(s) for s in specs)
    if not parsed:
        raise ParameterError("give at least one method spec")
    labels = [s.label for s in parsed]
    repeated = sorted({label for label in labels if labels.count(label) > 1})
    if repeated:
        raise ParameterError(
            f"method label(s) used twice: {', '.join(repeated)}; add '@LABEL' to tell them apart"
        )
    return parsed


def _validated(spec: MethodSpec) -> MethodSpec:
    try:
        _check_spec(spec)
    except ParameterError as error:
        raise ParameterError(f"method spec {spec.text!r}: {error}") from None
    return spec


def _check_spec(spec: MethodSpec) -> None:
    if not spec.is_truth:
        spec.extractor()
    elif spec.preset or spec.params:
        raise ParameterError(f"{TRUTH!r} takes no preset or parameters")


# --------------------------------------------------------------------------- scenes


def scene_seed(seed: int, sensor: str, index: int) -> int:
    """The seed of scene ``index`` of ``sensor`` in a run with base ``seed`` (32 bits)."""
    entropy = [int(seed), zlib.crc32(sensor.encode()), int(index)]
    return int(np.random.SeedSequence(entropy).generate_state(1, np.uint32)[0])


@dataclass(frozen=True, eq=False)
class SceneCase:
    """One scan to evaluate on, with its truth and where it came from.

    Attributes
    ----------
    sensor:
        Sensor preset name.
    index:
        Scene index within the sensor.
    seed:
        Seed of the scene layout and of the scan noise.
    kind:
        ``"room"`` or ``"corridor"``.
    noise:
        ``"realistic"`` or ``"exact"``.
    scan, truth:
        The simulated scan and its exact truth.
    """

    sensor: str
    index: int
    seed: int
    kind: str
    noise: str
    scan: Scan
    truth: Truth

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        # Scan does not pickle (it refuses attribute setting): send its arguments.
        scan = self.scan
        scan_args = (scan.ranges, scan.angle_min, scan.angle_increment)
        scan_args += (scan.range_min, scan.range_max, scan.pose)
        fields_ = (self.sensor, self.index, self.seed, self.kind, self.noise)
        return _rebuild_case, (fields_, scan_args, self.truth)


def _rebuild_case(fields_: tuple[Any, ...], scan_args: tuple[Any, ...], truth: Truth) -> SceneCase:
    *limits, pose = scan_args
    return SceneCase(*fields_, Scan(*limits, pose=pose), truth)


def make_scene(sensor: str, index: int, seed: int, noise: str = "realistic") -> SceneCase:
    """Generate scene ``index`` of ``sensor`` for base ``seed`` (see :func:`scene_seed`)."""
    _check_noise(noise)
    s = scene_seed(seed, sensor, index)
    scene = random_scene(s, sensor)
    sim = scene.scan(s, noise=NoiseModel() if noise == "exact" else None)
    return SceneCase(sensor, index, s, scene.kind, noise, sim.scan, sim.truth)


def iter_scenes(
    sensors: Sequence[str] | None = None,
    n: int = DEFAULT_SCENES,
    seed: int = 0,
    noise: str = "realistic",
) -> Iterator[SceneCase]:
    """Generate the scenes of a run: sensor by sensor, ``n`` each."""
    for sensor, index in _recipe(_check_sensors(sensors), n, seed, noise):
        yield make_scene(sensor, index, seed, noise)


def _recipe(sensors: Sequence[str], n: int, seed: int, noise: str) -> list[tuple[str, int]]:
    _check_noise(noise)
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ParameterError(f"scenes per sensor must be an integer >= 1, got {n!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError(f"seed must be an integer >= 0, got {seed!r}")
    return [(sensor, i) for sensor in sensors for i in range(n)]


def _check_noise(noise: str) -> None:
    if noise not in NOISES:
        raise ParameterError(f"noise must be one of {', '.join(NOISES)}, got {noise!r}")


def _check_sensors(sensors: Sequence[str] | None) -> tuple[str, ...]:
    chosen = tuple(SENSORS) if sensors is None else tuple(sensors)
    if not chosen:
        raise ParameterError("give at least one sensor")
    for name in chosen:
        get_sensor(name)
    if len(set(chosen)) != len(chosen):
        raise ParameterError(f"a sensor is given twice: {', '.join(chosen)}")
    return chosen


@dataclass(frozen=True, eq=False)
class SceneSet:
    """Scenes held in memory (generated, or loaded with :func:`load_scene_set`).

    Attributes
    ----------
    cases:
        The scenes, sensor by sensor.
    seed:
        Base seed they were generated with.
    noise:
        ``"realistic"`` or ``"exact"``.
    source:
        ``"generated"``, or the file they were loaded from.
    """

    cases: tuple[SceneCase, ...]
    seed: int
    noise: str
    source: str = "generated"

    def __len__(self) -> int:
        return len(self.cases)

    @property
    def sensors(self) -> tuple[str, ...]:
        """Sensor names in order of appearance."""
        return tuple(dict.fromkeys(c.sensor for c in self.cases))

    def per_sensor(self) -> dict[str, int]:
        """Number of scenes of each sensor."""
        return {s: sum(c.sensor == s for c in self.cases) for s in self.sensors}

    def select(self, sensors: Sequence[str] | None = None, n: int | None = None) -> SceneSet:
        """The scenes of ``sensors`` (all when ``None``), at most the first ``n`` of each.

        Raises
        ------
        ParameterError
            For a sensor the set does not hold, or ``n < 1``.
        """
        chosen = self.sensors if sensors is None else tuple(sensors)
        missing = [s for s in chosen if s not in self.sensors]
        if missing:
            raise ParameterError(
                f"scene set {self.source} has no scenes of {', '.join(missing)}; "
                f"it has {', '.join(self.sensors)}"
            )
        if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
            raise ParameterError(f"scenes per sensor must be an integer >= 1, got {n!r}")
        keep = [
            c
            for s in chosen
            for c in [c for c in self.cases if c.sensor == s][: n if n is not None else None]
        ]
        return SceneSet(tuple(keep), self.seed, self.noise, self.source)

    def find(self, sensor: str, index: int) -> SceneCase:
        """The scene ``index`` of ``sensor``."""
        for case in self.cases:
            if case.sensor == sensor and case.index == index:
                return case
        raise KeyError((sensor, index))

    def save(self, path: str | Path) -> Path:
        """Write the set to ``path`` (compressed ``.npz``, see the module docstring)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("wb") as handle:
            np.savez_compressed(handle, **_pack_cases(self))
        return path


def generate_scene_set(
    sensors: Sequence[str] | None = None,
    n: int = DEFAULT_SCENES,
    seed: int = 0,
    noise: str = "realistic",
    *,
    on_scene: OnScene | None = None,
) -> SceneSet:
    """Generate the scenes of a run into memory; ``on_scene(done, total)`` after each."""
    recipe = _recipe(_check_sensors(sensors), n, seed, noise)
    cases = []
    for done, (sensor, index) in enumerate(recipe, 1):
        cases.append(make_scene(sensor, index, seed, noise))
        if on_scene is not None:
            on_scene(done, len(recipe))
    return SceneSet(tuple(cases), seed, noise)


def save_scene_set(
    path: str | Path,
    sensors: Sequence[str] | None = None,
    n: int = DEFAULT_SCENES,
    seed: int = 0,
    noise: str = "realistic",
) -> Path:
    """Generate the scenes of a run and save them to ``path`` (``.npz``)."""
    return generate_scene_set(sensors, n, seed, noise).save(path)


# Ragged per-scene arrays, grouped by the count that sizes them.
_BEAM_FIELDS = ("edge", "true_ranges", "hit_points", "incidence", "on_curve", "status")
_BREAK_FIELDS = ("breakpoints", "breakpoint_runs")
_CORNER_FIELDS = ("corners", "corner_points", "corner_runs")
_SEGMENT_FIELDS = tuple(f.name for f in fields(TrueSegments))
_SCAN_FIELDS = ("angle_min", "angle_increment", "range_min", "range_max")


def _pack_cases(scenes: SceneSet) -> dict[str, np.ndarray]:
    cases = scenes.cases
    truths = [c.truth for c in cases]
    meta = {
        "format": SCENE_SET_FORMAT,
        "version": SCENE_SET_VERSION,
        "seed": scenes.seed,
        "noise": scenes.noise,
        "stores": "recipe and generated arrays: scans and their full truth",
    }
    out: dict[str, np.ndarray] = {
        "meta": np.array(json.dumps(meta)),
        "sensor": np.array([c.sensor for c in cases], dtype=str),
        "index": np.array([c.index for c in cases], dtype=np.int64),
        "seed": np.array([c.seed for c in cases], dtype=np.int64),
        "kind": np.array([c.kind for c in cases], dtype=str),
        "pose": np.array([t.pose for t in truths], dtype=np.float64).reshape(-1, 3),
        "full_circle": np.array([t.full_circle for t in truths], dtype=bool),
        "n_beams": np.array([t.n_beams for t in truths], dtype=np.int64),
        "n_breakpoints": np.array([len(t.breakpoints) for t in truths], dtype=np.int64),
        "n_corners": np.array([len(t.corners) for t in truths], dtype=np.int64),
        "n_segments": np.array([len(t.segments) for t in truths], dtype=np.int64),
        "ranges": _concat([c.scan.ranges for c in cases]),
    }
    for name in _SCAN_FIELDS:
        out[f"scan_{name}"] = np.array([getattr(c.scan, name) for c in cases], np.float64)
    for name in (*_BEAM_FIELDS, *_BREAK_FIELDS, *_CORNER_FIELDS):
        out[f"truth_{name}"] = _concat([getattr(t, name) for t in truths])
    for name in _SEGMENT_FIELDS:
        out[f"segment_{name}"] = _concat([getattr(t.segments, name) for t in truths])
    return out


def _concat(arrays: list[np.ndarray]) -> np.ndarray:
    return np.concatenate([np.asarray(a) for a in arrays]) if arrays else np.zeros(0)


def load_scene_set(path: str | Path) -> SceneSet:
    """Read a scene set written by :func:`save_scene_set` or :meth:`SceneSet.save`.

    Raises
    ------
    LogFormatError
        When the file is not a scene set or misses arrays.
    OSError
        When it cannot be read.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: data[key] for key in data.files}
        meta = json.loads(str(arrays["meta"]))
    except (ValueError, EOFError, KeyError, zlib.error) as error:
        raise LogFormatError(f"not a scene set (.npz): {error!r}", path=path) from None
    if meta.get("format") != SCENE_SET_FORMAT or meta.get("version") != SCENE_SET_VERSION:
        raise LogFormatError(f"not a {SCENE_SET_FORMAT} v{SCENE_SET_VERSION} file", path=path)
    try:
        cases = _unpack_cases(arrays, str(meta["noise"]))
    except (KeyError, ValueError, TypeError, IndexError) as error:
        raise LogFormatError(f"damaged scene set: {error!r}", path=path) from None
    return SceneSet(cases, int(meta["seed"]), str(meta["noise"]), str(path))


def _splits(counts: np.ndarray) -> list[slice]:
    ends = np.cumsum(counts)
    return [slice(int(e - c), int(e)) for c, e in zip(counts, ends, strict=True)]


def _part(
    a: Mapping[str, np.ndarray], prefix: str, names: tuple[str, ...], part: slice
) -> dict[str, np.ndarray]:
    return {name: _readonly(a[f"{prefix}{name}"][part]) for name in names}


def _unpack_cases(a: Mapping[str, np.ndarray], noise: str) -> tuple[SceneCase, ...]:
    beams, bps = _splits(a["n_beams"]), _splits(a["n_breakpoints"])
    corners, segs = _splits(a["n_corners"]), _splits(a["n_segments"])
    cases = []
    for k in range(len(a["sensor"])):
        pose = tuple(float(v) for v in a["pose"][k])
        truth = Truth(
            n_beams=int(a["n_beams"][k]),
            full_circle=bool(a["full_circle"][k]),
            pose=pose,
            **_part(a, "truth_", _BEAM_FIELDS, beams[k]),
            **_part(a, "truth_", _BREAK_FIELDS, bps[k]),
            **_part(a, "truth_", _CORNER_FIELDS, corners[k]),
            segments=TrueSegments(**_part(a, "segment_", _SEGMENT_FIELDS, segs[k])),
        )
        scan = Scan(
            a["ranges"][beams[k]],
            *(float(a[f"scan_{name}"][k]) for name in _SCAN_FIELDS),
            pose=pose,
        )
        sensor, index, seed, kind = (a[key][k] for key in ("sensor", "index", "seed", "kind"))
        cases.append(SceneCase(str(sensor), int(index), int(seed), str(kind), noise, scan, truth))
    return tuple(cases)


def _readonly(values: np.ndarray) -> np.ndarray:
    out = np.array(values)
    out.setflags(write=False)
    return out


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class EvalConfig:
    """What a run evaluated, stored with its results.

    Attributes
    ----------
    specs:
        The method specs.
    sensors:
        Sensor preset names.
    n:
        Scenes per sensor (the most of any sensor, for a loaded set).
    seed:
        Base seed.
    noise:
        ``"realistic"`` or ``"exact"``.
    tol:
        The tolerances every score was computed with.
    source:
        ``"generated"``, or the scene-set file.
    """

    specs: tuple[MethodSpec, ...]
    sensors: tuple[str, ...]
    n: int
    seed: int
    noise: str
    tol: Tolerances = field(default_factory=Tolerances)
    source: str = "generated"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (tolerances under ``"tolerances"``)."""
        return {
            "specs": [s.to_dict() for s in self.specs],
            "sensors": list(self.sensors),
            "scenes_per_sensor": self.n,
            "seed": self.seed,
            "noise": self.noise,
            "source": self.source,
            "scene_seed": "numpy.random.SeedSequence([seed, crc32(sensor), index])"
            ".generate_state(1, uint32)[0]",
            "tolerances": tolerances_dict(self.tol),
        }


@dataclass(frozen=True)
class ScanRecord:
    """The score of one spec on one scan, and its extraction time.

    Attributes
    ----------
    sensor, scene, seed, kind:
        The scene (see :class:`SceneCase`).
    spec:
        The method spec.
    us:
        Wall time of the extraction call, microseconds.
    nonfinite_lines:
        Found segments whose line (``Extraction.lines`` row) is not finite; they
        match nothing and make the environmental similarity NaN.
    score:
        The scores.
    """

    sensor: str
    scene: int
    seed: int
    kind: str
    spec: MethodSpec
    us: float
    nonfinite_lines: int
    score: ScanScore

    def to_dict(self) -> dict[str, Any]:
        """One per-scan CSV row."""
        return {
            "sensor": self.sensor,
            "scene": self.scene,
            "seed": self.seed,
            "kind": self.kind,
            **_spec_columns(self.spec),
            "us": self.us,
            "nonfinite_lines": self.nonfinite_lines,
            **self.score.to_dict(),
        }


@dataclass(frozen=True)
class SummaryRecord:
    """Scores of one spec pooled over the scans of one sensor (or of all)."""

    sensor: str
    spec: MethodSpec
    summary: Summary
    median_us: float
    mean_us: float
    nonfinite_lines: int = 0

    def to_dict(self) -> dict[str, Any]:
        """One summary CSV row."""
        return {
            "sensor": self.sensor,
            **_spec_columns(self.spec),
            "median_us": self.median_us,
            "mean_us": self.mean_us,
            "nonfinite_lines": self.nonfinite_lines,
            **self.summary.to_dict(),
        }


def _spec_columns(spec: MethodSpec) -> dict[str, Any]:
    return {
        "label": spec.label,
        "method": spec.method,
        "preset": spec.preset or "",
        "params": spec.params_text,
    }


@dataclass(frozen=True)
class WorstScan:
    """A scan ranked by :func:`worst_scans`, with each spec's event F1 on it."""

    sensor: str
    scene: int
    seed: int
    score: float
    f1_by_label: tuple[tuple[str, float], ...]


@dataclass(frozen=True, eq=False)
class EvalResult:
    """Per-scan and pooled scores of a run.

    Attributes
    ----------
    config:
        What was evaluated.
    records:
        One per (scene, spec), sensor by sensor, scene by scene, spec by spec.
    summaries:
        One per (sensor, spec), then one per spec pooled over all sensors
        (``sensor == "all"``) when there is more than one sensor.
    scenes:
        The scene set evaluated on, when it was given (else scenes are regenerated
        on demand by :meth:`case`).
    """

    config: EvalConfig
    records: tuple[ScanRecord, ...]
    summaries: tuple[SummaryRecord, ...]
    scenes: SceneSet | None = None

    def summary(self, sensor: str, label: str) -> SummaryRecord:
        """The pooled scores of spec ``label`` on ``sensor`` (or ``"all"``)."""
        for rec in self.summaries:
            if rec.sensor == sensor and rec.spec.label == label:
                return rec
        raise KeyError((sensor, label))

    def per_scan_rows(self) -> list[dict[str, Any]]:
        """Per-scan rows (see :meth:`ScanRecord.to_dict`)."""
        return [r.to_dict() for r in self.records]

    def summary_rows(self) -> list[dict[str, Any]]:
        """Summary rows (see :meth:`SummaryRecord.to_dict`)."""
        return [r.to_dict() for r in self.summaries]

    def to_csv(self, directory: str | Path) -> tuple[Path, Path]:
        """Write ``per_scan.csv`` and ``summary.csv`` into ``directory``.

        Every row carries the tolerances as ``tol_*`` columns.
        """
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        return (
            _write_csv(directory / "per_scan.csv", self.per_scan_rows()),
            _write_csv(directory / "summary.csv", self.summary_rows()),
        )

    def to_dict(self, *, per_scan: bool = False) -> dict[str, Any]:
        """Config, tolerances, summary rows (and per-scan rows); NaN becomes ``None``."""
        out: dict[str, Any] = {
            "tolerances": tolerances_dict(self.config.tol),
            "config": self.config.to_dict(),
            "worst_by": WORST_BY,
            "summary": self.summary_rows(),
        }
        if per_scan:
            out["per_scan"] = self.per_scan_rows()
        return _jsonable(out)

    def to_json(self, path: str | Path, *, per_scan: bool = False) -> Path:
        """Write :meth:`to_dict` to ``path``."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(per_scan=per_scan), indent=2) + "\n")
        return path

    def case(self, sensor: str, index: int) -> SceneCase:
        """Scene ``index`` of ``sensor``: from the scene set, or generated again."""
        if self.scenes is not None:
            return self.scenes.find(sensor, index)
        return make_scene(sensor, index, self.config.seed, self.config.noise)

    def table(self, sensor: str) -> list[list[str]]:
        """Formatted :data:`TABLE_COLUMNS` rows of the summaries of ``sensor``."""
        return [
            [rec.spec.label, *(_format(fn(rec), fmt) for _, fn, fmt in TABLE_COLUMNS)]
            for rec in self.summaries
            if rec.sensor == sensor
        ]


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> Path:
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]) if rows else [])
        writer.writeheader()
        writer.writerows(rows)
    return path


def tolerances_dict(tol: Tolerances) -> dict[str, Any]:
    """:meth:`Tolerances.to_dict` plus ``alpha_deg``."""
    return tol.to_dict() | {"alpha_deg": math.degrees(tol.alpha)}


def tolerance_caption(tol: Tolerances) -> str:
    """One line stating the tolerances, for table captions and figure titles."""
    return (
        f"tolerances: events +-{tol.event_beams} beams; segments |drho| <= "
        f"{100 * tol.rho:g} cm, |dalpha| <= {math.degrees(tol.alpha):g} deg, overlap >= "
        f"{tol.overlap:g}; don't care: segments < {tol.min_segment_beams} beams, events "
        f"next to runs < {tol.min_run} returns"
        + (", unmatched on curved surfaces" if tol.curved_dont_care else "")
    )


def _format(value: float, fmt: str) -> str:
    if isinstance(value, float) and math.isnan(value):
        return "-"
    return format(value, fmt)


TABLE_COLUMNS: tuple[tuple[str, Callable[[SummaryRecord], float], str], ...] = (
    ("bp P", lambda r: r.summary.breakpoints.precision, ".3f"),
    ("bp R", lambda r: r.summary.breakpoints.recall, ".3f"),
    ("bp F1", lambda r: r.summary.breakpoints.f1, ".3f"),
    ("corner P", lambda r: r.summary.corners.precision, ".3f"),
    ("corner R", lambda r: r.summary.corners.recall, ".3f"),
    ("corner F1", lambda r: r.summary.corners.f1, ".3f"),
    ("TruePos", lambda r: r.summary.segments.true_pos, ".3f"),
    ("FalsePos", lambda r: r.summary.segments.false_pos, ".3f"),
    ("split", lambda r: r.summary.segments.split, "d"),
    ("merge", lambda r: r.summary.segments.merge, "d"),
    ("|drho| cm", lambda r: 100 * r.summary.segments.mean_abs_drho, ".2f"),
    ("|dalpha| deg", lambda r: math.degrees(r.summary.segments.mean_abs_dalpha), ".2f"),
    ("sim. cm", lambda r: 100 * r.summary.similarity.mean, ".2f"),
    ("accuracy", lambda r: r.summary.accuracy_rate_mean, ".3f"),
    ("us/scan", lambda r: r.median_us, ".0f"),
)
"""Table columns: header, value of a :class:`SummaryRecord`, format. Rates are pooled
(micro-averaged) over the scans; split and merge are totals; ``accuracy`` is the mean
per-scan accuracy rate; ``sim. cm`` the mean environmental-similarity error;
``us/scan`` the median extraction time."""


# --------------------------------------------------------------------------- the truth row


def truth_extraction(scan: Scan, truth: Truth, *, range_sigma: float = 0.0) -> Extraction:
    """The truth row of a scan: its true segments fitted to its own measured returns.

    Every true segment becomes one segment over the same beams (``first`` and
    ``last`` from the truth), fitted by total least squares, as the methods fit
    (:func:`scanlines.steps.assemble.assemble`), to the scan's returns in that run
    that the truth says hit the segment's edge (:attr:`Truth.true_return`: no
    outliers, mixed pixels or dropouts). Breakpoints and corners are the true ones;
    outliers are the returns of no surface (outliers and mixed pixels).

    Parameters
    ----------
    scan, truth:
        A simulated scan and its truth.
    range_sigma:
        Range noise in metres for the segments' covariances (they are not scored).

    Returns
    -------
    Extraction
        With ``method == "truth"``: the best any segmentation can do with exact
        boundaries.
    """
    seg, n = truth.segments, truth.n_beams
    spans = (seg.last - seg.first) % n + 1
    beams, owner = run_labels(seg.first, seg.first + spans - 1, n)
    beams %= n  # a segment across the seam of a full circle
    keep = scan.valid[beams] & truth.true_return[beams] & (truth.edge[beams] == seg.edge[owner])
    beams, owner = beams[keep], owner[keep]
    b = np.cumsum(np.bincount(owner, minlength=len(seg))) - 1
    a = np.concatenate(([0], b[:-1] + 1)).astype(np.intp)
    r, bearing = scan.ranges[beams], scan.angle_increment * beams  # beam 0 at bearing 0
    returns = Returns(beams, r, r * np.cos(bearing), r * np.sin(bearing))
    arrays = assemble(
        returns, TLS, prefix_moments(returns.x, returns.y), a.astype(np.int64), b,
        scan.angle_min, float(range_sigma), truth.breakpoints.astype(np.int64),
        truth.corners.astype(np.int64),
        np.union1d(truth.outliers, truth.mixed_pixels).astype(np.int64),
    )  # fmt: skip
    return to_extraction(arrays, TRUTH, {"range_sigma": range_sigma})


def _truth_row(case: SceneCase) -> Extraction:
    """:func:`truth_extraction` of a scene, covariances from its preset's range noise."""
    sigma = get_sensor(case.sensor).noise.sigma if case.noise == "realistic" else 0.0
    return truth_extraction(case.scan, case.truth, range_sigma=sigma)


# --------------------------------------------------------------------------- running


def evaluate(
    specs: Iterable[str | MethodSpec],
    sensors: Sequence[str] | None = None,
    n: int | None = None,
    seed: int = 0,
    *,
    tol: Tolerances | None = None,
    noise: str = "realistic",
    scenes: SceneSet | None = None,
    workers: int = 1,
    on_scene: OnScene | None = None,
) -> EvalResult:
    """Run every spec on the same scans and score them against the truth.

    Parameters
    ----------
    specs:
        Method specs (strings as in :func:`parse_spec`, or :class:`MethodSpec`).
    sensors:
        Sensor preset names; all of :data:`~scanlines.sim.SENSORS` when ``None``.
        With ``scenes``, a selection of the set's sensors.
    n:
        Scenes per sensor; 100 when ``None``. With ``scenes``, at most this many of
        each sensor (all when ``None``).
    seed:
        Base seed (see :func:`scene_seed`); ignored with ``scenes``.
    tol:
        Tolerances; :class:`~scanlines.metrics.Tolerances` defaults when ``None``.
    noise:
        ``"realistic"`` or ``"exact"``; ignored with ``scenes``.
    scenes:
        Evaluate on this set instead of generating scenes.
    workers:
        Processes; each scene is generated once and all specs run on it.
    on_scene:
        Called as ``on_scene(done, total)`` after each scene.

    Returns
    -------
    EvalResult

    Raises
    ------
    ParameterError
        For a bad spec, an unknown sensor, ``n < 1``, a negative seed, an unknown
        noise or ``workers < 1``.
    """
    parsed = parse_specs(specs)
    tol = Tolerances() if tol is None else tol
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers must be an integer >= 1, got {workers!r}")
    if scenes is not None:
        scenes = scenes.select(sensors, n)
        jobs: list[Any] = list(scenes.cases)
        counts = scenes.per_sensor()
        config = EvalConfig(
            parsed,
            scenes.sensors,
            max(counts.values(), default=0),
            scenes.seed,
            scenes.noise,
            tol,
            scenes.source,
        )
    else:
        chosen = _check_sensors(sensors)
        n = DEFAULT_SCENES if n is None else n
        jobs = [(s, i, seed, noise) for s, i in _recipe(chosen, n, seed, noise)]
        config = EvalConfig(parsed, chosen, n, seed, noise, tol)
    records = [r for batch in _run_jobs(jobs, parsed, tol, workers, on_scene) for r in batch]
    return EvalResult(config, tuple(records), _summarise(records, config), scenes)


def _run_jobs(
    jobs: list[Any],
    specs: tuple[MethodSpec, ...],
    tol: Tolerances,
    workers: int,
    on_scene: OnScene | None,
) -> Iterator[list[ScanRecord]]:
    work = partial(_run_job, specs=specs, tol=tol)
    if workers == 1 or len(jobs) < 2:
        results: Iterable[list[ScanRecord]] = map(work, jobs)
        yield from _counted(results, len(jobs), on_scene)
        return
    from concurrent.futures import ProcessPoolExecutor

    chunk = max(1, len(jobs) // (8 * workers))
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield from _counted(pool.map(work, jobs, chunksize=chunk), len(jobs), on_scene)


def _counted(
    results: Iterable[list[ScanRecord]], total: int, on_scene: OnScene | None
) -> Iterator[list[ScanRecord]]:
    for done, batch in enumerate(results, 1):
        if on_scene is not None:
            on_scene(done, total)
        yield batch


Runner = Callable[[SceneCase], "Extraction"]


@lru_cache(maxsize=8)
def _runners(specs: tuple[MethodSpec, ...]) -> tuple[Runner, ...]:
    """What each spec does with a scene: its extractor on the scan, or the truth row."""
    return tuple(_truth_row if s.is_truth else _on_scan(s.extractor()) for s in specs)


def _on_scan(extractor: Extractor) -> Runner:
    return lambda case: extractor(case.scan)


_WARM: set[tuple[MethodSpec, ...]] = set()


def _run_job(
    job: SceneCase | tuple[str, int, int, str], *, specs: tuple[MethodSpec, ...], tol: Tolerances
) -> list[ScanRecord]:
    """Score every spec on one scene (generated here from its recipe, or given).

    The first scene a process sees is extracted once untimed per spec, so that
    one-off costs (lazy imports, caches) do not land in the times. Each timed
    extraction follows an untimed one of the same spec on the same scan: after
    generating a scene or scoring the previous spec the processor's caches are cold,
    and a time taken then depends on what ran before (the same configuration under
    two labels measured 155 and 73 us; now 64 and 52 us). The first spec still
    measures 10-20 % slower than the same configuration later in the list: compare
    speeds with ``scanlines bench``, which times each method over many scans in turn.
    """
    case = job if isinstance(job, SceneCase) else make_scene(*job)
    runners = _runners(specs)
    if specs not in _WARM:
        for runner in runners:
            runner(case)
        _WARM.add(specs)
    out = []
    for spec, runner in zip(specs, runners, strict=True):
        runner(case)
        start = time.perf_counter_ns()
        extraction = runner(case)
        us = (time.perf_counter_ns() - start) / 1000.0
        out.append(
            ScanRecord(
                case.sensor,
                case.index,
                case.seed,
                case.kind,
                spec,
                us,
                int(np.count_nonzero(~np.isfinite(extraction.lines).all(axis=1))),
                score(extraction, case.truth, case.scan, tol),
            )
        )
    return out


def _summarise(records: list[ScanRecord], config: EvalConfig) -> tuple[SummaryRecord, ...]:
    groups = [*config.sensors, ALL_SENSORS] if len(config.sensors) > 1 else [*config.sensors]
    out = []
    for sensor in groups:
        for spec in config.specs:
            chosen = [
                r
                for r in records
                if r.spec.label == spec.label and sensor in (ALL_SENSORS, r.sensor)
            ]
            if chosen:
                us = np.array([r.us for r in chosen])
                out.append(
                    SummaryRecord(
                        sensor,
                        spec,
                        aggregate(r.score for r in chosen),
                        float(np.median(us)),
                        float(us.mean()),
                        sum(r.nonfinite_lines for r in chosen),
                    )
                )
    return tuple(out)


# --------------------------------------------------------------------------- worst scans


def event_f1(s: ScanScore) -> float:
    """F1 of breakpoints and corners pooled; 1 when nothing counted was true or found."""
    tp = s.breakpoints.tp + s.corners.tp
    wrong = s.breakpoints.fp + s.breakpoints.fn + s.corners.fp + s.corners.fn
    return 2 * tp / (2 * tp + wrong) if 2 * tp + wrong else 1.0


def worst_scans(result: EvalResult, k: int = 4) -> tuple[WorstScan, ...]:
    """The ``k`` scans with the lowest mean event F1 over the specs (see :data:`WORST_BY`).

    Ties go to the scan with more event errors, then to sensor and scene order.
    """
    by_scan: dict[tuple[str, int], list[ScanRecord]] = {}
    for rec in result.records:
        by_scan.setdefault((rec.sensor, rec.scene), []).append(rec)
    ranked = []
    for order, ((sensor, scene), recs) in enumerate(by_scan.items()):
        f1 = np.array([event_f1(r.score) for r in recs])
        errors = sum(
            r.score.breakpoints.fp
            + r.score.breakpoints.fn
            + r.score.corners.fp
            + r.score.corners.fn
            for r in recs
        )
        worst = WorstScan(
            sensor,
            scene,
            recs[0].seed,
            float(f1.mean()),
            tuple((r.spec.label, float(v)) for r, v in zip(recs, f1, strict=True)),
        )
        ranked.append((worst.score, -errors, order, worst))
    ranked.sort(key=lambda item: item[:3])
    return tuple(item[3] for item in ranked[: max(0, k)])


# --------------------------------------------------------------------------- plots


TRUTH_LINE = "#000000"
TRUTH_MARK = "#ffb000"
"""Colours of the truth: dashed black segments, faint amber event markers."""


def plot_truth_overlay(
    scan: Scan,
    truth: Truth,
    extraction: Extraction,
    ax: Axes | None = None,
    *,
    title: str | None = None,
    legend: bool = True,
) -> Axes:
    """Draw detections (as :func:`scanlines.plot.plot_extraction`) over the truth.

    True segments are thin dashed black lines; true breakpoints (the exact hit point
    of the beam) large faint amber circles; true corners (the vertex) large faint amber
    diamonds. Detections keep their look: solid segments, hollow red triangles
    (breakpoints), hollow black squares (corners). Sensor frame, metres.
    """
    from scanlines.plot import _pyplot, plot_extraction

    if ax is None:
        _, ax = _pyplot().subplots(figsize=(7, 7))
    seg = truth.segments
    xs = np.column_stack((seg.start[:, 0], seg.end[:, 0], np.full(len(seg), np.nan))).ravel()
    ys = np.column_stack((seg.start[:, 1], seg.end[:, 1], np.full(len(seg), np.nan))).ravel()
    ax.plot(xs, ys, "--", c=TRUTH_LINE, lw=1.0, zorder=4, label="true segments")
    bp = truth.hit_points[truth.breakpoints]
    ax.plot(
        *bp.T, "o", ms=13, c=TRUTH_MARK, alpha=0.5, ls="none", zorder=0, label="true breakpoints"
    )
    corners = truth.corner_points
    ax.plot(
        *corners.T,
        "D",
        ms=12,
        c=TRUTH_MARK,
        alpha=0.5,
        ls="none",
        zorder=0,
        label="true corners",
    )
    plot_extraction(scan, extraction, ax, title=title, legend=False)
    if legend:
        ax.legend(loc="best", fontsize=7, markerscale=0.8)
    return ax


def plot_worst(result: EvalResult, k: int = 4, *, size: float = 4.2) -> Figure:
    """The ``k`` worst scans (:func:`worst_scans`), one row each, one column per spec."""
    from scanlines.plot import _pyplot

    plt = _pyplot()
    worst = worst_scans(result, k)
    specs = result.config.specs
    rows, cols = max(1, len(worst)), len(specs)
    width, height = max(size * cols, 7.0), size * rows + 1.6  # 1.6 in: title and legend
    fig, axes = plt.subplots(rows, cols, figsize=(width, height), squeeze=False)
    runners = _runners(specs)
    for row, item in zip(axes, worst, strict=False):
        case = result.case(item.sensor, item.scene)
        for ax, spec, runner, (_, f1) in zip(row, specs, runners, item.f1_by_label, strict=True):
            title = f"{spec.label} | {item.sensor} #{item.scene} ({case.kind})\nevent F1 {f1:.2f}"
            plot_truth_overlay(case.scan, case.truth, runner(case), ax, title=title, legend=False)
    if not worst:
        for ax in axes.flat:
            ax.axis("off")
    handles, labels = _overlay_legend(axes)
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    text = f"Worst {len(worst)} scans by {WORST_BY}. {tolerance_caption(result.config.tol)}"
    fig.suptitle(_wrapped(text, width), fontsize=8)
    fig.tight_layout(rect=(0, 0.8 / height, 1, 1 - 0.8 / height))
    return fig


def _wrapped(text: str, width_inches: float) -> str:
    """``text`` broken into lines that fit a figure ``width_inches`` wide at 8 pt."""
    import textwrap

    return textwrap.fill(text, width=max(40, int(15 * width_inches)))


def _overlay_legend(axes: np.ndarray) -> tuple[list[Any], list[str]]:
    seen: dict[str, Any] = {}
    for ax in axes.flat:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(label, handle)
    return list(seen.values()), list(seen)


BAR_METRICS: tuple[tuple[str, Callable[[Summary], float]], ...] = (
    ("breakpoint F1", lambda s: s.breakpoints.f1),
    ("corner F1", lambda s: s.corners.f1),
    ("segment TruePos", lambda s: s.segments.true_pos),
    ("segment FalsePos", lambda s: s.segments.false_pos),
)
"""The metrics of :func:`plot_bars`."""


def plot_bars(result: EvalResult, *, size: float = 4.0) -> Figure:
    """Grouped bars per sensor: :data:`BAR_METRICS` (groups) by spec (bars)."""
    from scanlines.plot import _pyplot

    plt = _pyplot()
    palette = plt.get_cmap("tab20").colors  # one colour per spec, up to 20
    sensors = list(dict.fromkeys(r.sensor for r in result.summaries))
    specs = result.config.specs
    fig, axes = plt.subplots(
        1, len(sensors), figsize=(size * len(sensors), size), squeeze=False, sharey=True
    )
    x = np.arange(len(BAR_METRICS))
    width = 0.8 / len(specs)
    for ax, sensor in zip(axes[0], sensors, strict=True):
        for j, spec in enumerate(specs):
            summary = result.summary(sensor, spec.label).summary
            values = [fn(summary) for _, fn in BAR_METRICS]
            ax.bar(
                x + (j - (len(specs) - 1) / 2) * width,
                values,
                width,
                label=spec.label,
                color=palette[j % len(palette)],
            )
        n_scans = result.summary(sensor, specs[0].label).summary.n_scans
        ax.set_title(f"{sensor} ({n_scans} scans)", fontsize=10)
        ax.set_xticks(x, [name for name, _ in BAR_METRICS], rotation=25, ha="right", fontsize=8)
        ax.set_ylim(0, 1.05)
        ax.grid(True, axis="y", lw=0.3)
    axes[0, 0].set_ylabel("rate (FalsePos: lower is better)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(_wrapped(tolerance_caption(result.config.tol), size * len(sensors)), fontsize=8)
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- helpers


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value
