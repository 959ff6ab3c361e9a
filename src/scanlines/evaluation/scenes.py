"""The simulated scenes an evaluation runs on, and scene sets saved to files.

Scenes and seeds
----------------
Scene ``i`` of sensor ``s`` is ``random_scene(seed_i, s).scan(seed_i)`` with
``seed_i = scene_seed(seed, s, i)``: a 32-bit integer from
``numpy.random.SeedSequence([seed, crc32(s), i])`` (``random_scene(seed_i, s,
clutter=True)`` for clutter scenes). Every method spec sees the same
scans, and the same arguments give the same numbers on every run. Noise is the preset's
realistic model (``"realistic"``) or none (``"exact"``, ``NoiseModel()``).

Scene sets
----------
:meth:`SceneSet.save` writes a compressed ``.npz`` holding, for every scene, the
recipe (sensor, index, seed, kind, noise) *and* the generated data: the scan
(ranges, beam layout, range limits, pose) and every array of its
:class:`~scanlines.evaluation.truth.Truth`. :func:`load_scene_set` rebuilds the scans
and truths from the arrays alone, so a saved set stays fixed when the simulator
changes. The world geometry is not stored (scoring and plots do not need it).
"""

from __future__ import annotations

import json
import zlib
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from scanlines import LogFormatError, ParameterError, Scan
from scanlines.errors import NO_SUCH_FILE
from scanlines.sim import SENSORS, NoiseModel, get_sensor, random_scene
from scanlines.truth import TrueSegments, Truth

__all__ = [
    "DEFAULT_SCENES",
    "NOISES",
    "OnScene",
    "SceneCase",
    "SceneSet",
    "check_sensors",
    "generate_scene_set",
    "iter_scenes",
    "load_scene_set",
    "make_scene",
    "scene_recipe",
    "scene_seed",
]

NOISES = ("realistic", "exact")
"""Noise choices: the sensor preset's own model, or exact ranges."""

DEFAULT_SCENES = 100
"""Scenes per sensor when generating and none is given."""

SCENE_SET_FORMAT = "scanlines-scene-set"
SCENE_SET_VERSION = 1

OnScene = Callable[[int, int], None]
"""``on_scene(done, total)``: called after each scene."""


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
        The scene kind (:data:`scanlines.sim.SCENE_KINDS` or ``CLUTTER_KINDS``).
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


def make_scene(
    sensor: str, index: int, seed: int, noise: str = "realistic", clutter: bool = False
) -> SceneCase:
    """Generate scene ``index`` of ``sensor`` for base ``seed`` (see :func:`scene_seed`).

    ``clutter``: a clutter scene (:data:`scanlines.sim.CLUTTER_KINDS`).
    """
    _check_noise(noise)
    s = scene_seed(seed, sensor, index)
    scene = random_scene(s, sensor, clutter=clutter)
    sim = scene.scan(s, noise=NoiseModel() if noise == "exact" else None)
    return SceneCase(sensor, index, s, scene.kind, noise, sim.scan, sim.truth)


def iter_scenes(
    sensors: Sequence[str] | None = None,
    n: int = DEFAULT_SCENES,
    seed: int = 0,
    noise: str = "realistic",
    clutter: bool = False,
) -> Iterator[SceneCase]:
    """Generate the scenes of a run: sensor by sensor, ``n`` each."""
    for sensor, index in scene_recipe(check_sensors(sensors), n, seed, noise):
        yield make_scene(sensor, index, seed, noise, clutter)


def scene_recipe(sensors: Sequence[str], n: int, seed: int, noise: str) -> list[tuple[str, int]]:
    """``(sensor, index)`` of every scene of a run, sensor by sensor (arguments checked)."""
    _check_noise(noise)
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ParameterError(f"scenes per sensor must be an integer >= 1, got {n!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError(f"seed must be an integer >= 0, got {seed!r}")
    return [(sensor, i) for sensor in sensors for i in range(n)]


def _check_noise(noise: str) -> None:
    if noise not in NOISES:
        raise ParameterError(f"noise must be one of {', '.join(NOISES)}, got {noise!r}")


def check_sensors(sensors: Sequence[str] | None) -> tuple[str, ...]:
    """The sensor presets of a run: ``sensors`` checked, or all of them for ``None``."""
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
    clutter:
        Whether they are clutter scenes.
    """

    cases: tuple[SceneCase, ...]
    seed: int
    noise: str
    source: str = "generated"
    clutter: bool = False

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
        return SceneSet(tuple(keep), self.seed, self.noise, self.source, self.clutter)

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
    clutter: bool = False,
    on_scene: OnScene | None = None,
) -> SceneSet:
    """Generate the scenes of a run into memory; ``on_scene(done, total)`` after each."""
    recipe = scene_recipe(check_sensors(sensors), n, seed, noise)
    cases = []
    for done, (sensor, index) in enumerate(recipe, 1):
        cases.append(make_scene(sensor, index, seed, noise, clutter))
        if on_scene is not None:
            on_scene(done, len(recipe))
    return SceneSet(tuple(cases), seed, noise, clutter=clutter)


# Ragged per-scene arrays, grouped by the count that sizes them.
_BEAM_FIELDS = ("edge", "true_ranges", "hit_points", "incidence", "on_curve", "status")
_BREAK_FIELDS = ("breakpoints", "breakpoint_runs")
_CORNER_FIELDS = ("corners", "corner_points", "corner_runs")
# Stored since the truth has them; a set written before reads as "none".
_OPTIONAL_FIELDS = {"breakpoint_dont_care": "n_breakpoints", "corner_dont_care": "n_corners"}
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
        "clutter": scenes.clutter,
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
    for name in (*_BEAM_FIELDS, *_BREAK_FIELDS, *_CORNER_FIELDS, *_OPTIONAL_FIELDS):
        out[f"truth_{name}"] = _concat([getattr(t, name) for t in truths])
    for name in _SEGMENT_FIELDS:
        out[f"segment_{name}"] = _concat([getattr(t.segments, name) for t in truths])
    return out


def _concat(arrays: list[np.ndarray]) -> np.ndarray:
    return np.concatenate([np.asarray(a) for a in arrays]) if arrays else np.zeros(0)


def load_scene_set(path: str | Path) -> SceneSet:
    """Read a scene set written by :meth:`SceneSet.save`.

    Raises
    ------
    LogFormatError
        When the file is not a scene set or misses arrays.
    OSError
        When it cannot be read.
    """
    path = Path(path)
    if not path.exists():
        raise LogFormatError(NO_SUCH_FILE, path=path)
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
    clutter = bool(meta.get("clutter", False))
    return SceneSet(cases, int(meta["seed"]), str(meta["noise"]), str(path), clutter)


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
            **{
                name: _readonly(
                    a[f"truth_{name}"][(bps if count == "n_breakpoints" else corners)[k]]
                )
                for name, count in _OPTIONAL_FIELDS.items()
                if f"truth_{name}" in a
            },
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
