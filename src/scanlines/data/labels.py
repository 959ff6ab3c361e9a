"""Hand labels of breakpoints and corners for frames of the shipped sample logs.

One label file per sensor (:data:`LABEL_FILES`): the Intel Research Lab excerpt (SICK
at 1 deg), Freiburg 079 (SICK at 0.5 deg) and the URG-04LX excerpt, each labelled by
hand from plots (range against beam, and the x-y points annotated with their beam
index), with no extraction method consulted. The labelling rule and how the frames
were chosen are stored in each file; see also ``PROVENANCE.md``::

    from scanlines.data.labels import label_set
    labels = label_set("urg")
    for frame in labels.frames:
        frame.scan, frame.breakpoints, frame.corners
    print(labels.rule)

Beam indices are 0-based into the scan; scan indices are 0-based into the excerpt, in
the order ``scanlines.io.open_log(scanlines.data.sample(name))`` yields them. The
``uncertain_*`` lists hold events the labeller could not decide; a scorer should treat
them as "don't care" (neither a miss nor a false positive).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ScanlinesError

__all__ = [
    "INTEL_LABELS",
    "LABEL_FILES",
    "LabelError",
    "LabelSet",
    "LabelledFrame",
    "intel_label_rule",
    "intel_label_set",
    "intel_labels",
    "label_log_options",
    "label_set",
    "labelled_samples",
    "read_labels",
]

_HERE = Path(__file__).resolve().parent

#: The label file of the Intel excerpt, inside this package.
INTEL_LABELS = _HERE / "intel_labels.json"

_TOP_KEYS = ("source", "beams", "angle_convention", "how_chosen", "rule", "labeller", "frames")
_INDEX_KEYS = ("breakpoints", "corners", "uncertain_breakpoints", "uncertain_corners")
_FRAME_KEYS = ("scan", *_INDEX_KEYS, "notes")


class LabelError(ScanlinesError, ValueError):
    """A label file is malformed or does not fit the log it labels."""


@dataclass(frozen=True)
class LabelledFrame:
    """The hand labels of one scan.

    Attributes
    ----------
    scan:
        Index of the scan in the log (0-based, in reading order).
    breakpoints:
        Beams reported as breakpoints (the last valid beam before a discontinuity).
    corners:
        Beams nearest the vertex of a corner.
    uncertain_breakpoints, uncertain_corners:
        Events the labeller could not decide ("don't care" when scoring).
    notes:
        Free text: what the scan shows and why hard cases were labelled as they were.
    """

    scan: int
    breakpoints: tuple[int, ...]
    corners: tuple[int, ...]
    uncertain_breakpoints: tuple[int, ...] = ()
    uncertain_corners: tuple[int, ...] = ()
    notes: str = ""


@dataclass(frozen=True)
class LabelSet:
    """A whole label file: its metadata and its frames, in file order."""

    source: str
    beams: int
    angle_convention: str
    how_chosen: str
    rule: str
    labeller: str
    frames: tuple[LabelledFrame, ...]


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _indices(where: str, key: str, value: Any, beams: int) -> tuple[int, ...]:
    if not isinstance(value, list):
        raise LabelError(f"{where}: {key} must be a list of beam indices, got {value!r}")
    for item in value:
        if not _is_int(item):
            raise LabelError(f"{where}: {key} must hold integers, got {item!r}")
        if not 0 <= item < beams:
            raise LabelError(f"{where}: {key}: beam {item} out of range 0..{beams - 1}")
    for a, b in pairwise(value):
        if b <= a:
            what = "repeated" if a == b else "not sorted"
            raise LabelError(f"{where}: {key} {what} at beam {b} (after {a}): {value}")
    return tuple(value)


def _frame(where: str, raw: Any, beams: int) -> LabelledFrame:
    if not isinstance(raw, Mapping):
        raise LabelError(f"{where}: a frame must be an object, got {type(raw).__name__}")
    missing = [k for k in _FRAME_KEYS if k not in raw]
    unknown = sorted(k for k in raw if k not in _FRAME_KEYS)
    if missing:
        raise LabelError(f"{where}: missing key(s) {', '.join(missing)}")
    if unknown:
        raise LabelError(
            f"{where}: unknown key(s) {', '.join(unknown)}; keys: {', '.join(_FRAME_KEYS)}"
        )
    scan = raw["scan"]
    if not _is_int(scan) or scan < 0:
        raise LabelError(f"{where}: scan must be a non-negative integer, got {scan!r}")
    where = f"{where} (scan {scan})"
    if not isinstance(raw["notes"], str):
        raise LabelError(f"{where}: notes must be a string, got {raw['notes']!r}")
    lists = {key: _indices(where, key, raw[key], beams) for key in _INDEX_KEYS}
    for kind in ("breakpoints", "corners"):
        both = sorted(set(lists[kind]) & set(lists[f"uncertain_{kind}"]))
        if both:
            raise LabelError(f"{where}: beam(s) {both} are in both {kind} and uncertain_{kind}")
    ends = sorted({0, beams - 1} & set(lists["breakpoints"]))
    if ends:
        raise LabelError(
            f"{where}: breakpoints at the first or last beam {ends}; the rule excludes them "
            "(list them under uncertain_breakpoints)"
        )
    return LabelledFrame(scan=scan, notes=raw["notes"], **lists)


def read_labels(path: str | Path, valid: Sequence[np.ndarray] | None = None) -> LabelSet:
    """Read and validate a label file.

    Parameters
    ----------
    path:
        The JSON file (layout of ``intel_labels.json``).
    valid:
        Optional per-scan "has a return" masks of the labelled log, indexed by scan
        index. When given, every scan index must exist, every mask must have
        ``beams`` entries and every labelled beam (certain or uncertain) must be a
        valid return.

    Raises
    ------
    LabelError
        On any problem; the message names the file, the frame, the list and the beam.
    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise LabelError(f"{path}: cannot read label file: {exc}") from exc
    if not isinstance(doc, Mapping):
        raise LabelError(f"{path}: the top level must be an object")
    missing = [k for k in _TOP_KEYS if k not in doc]
    if missing:
        raise LabelError(f"{path}: missing key(s) {', '.join(missing)}")
    beams = doc["beams"]
    if not _is_int(beams) or beams < 1:
        raise LabelError(f"{path}: beams must be a positive integer, got {beams!r}")
    for key in ("source", "angle_convention", "how_chosen", "rule", "labeller"):
        if not isinstance(doc[key], str) or not doc[key].strip():
            raise LabelError(f"{path}: {key} must be a non-empty string")
    raw_frames = doc["frames"]
    if not isinstance(raw_frames, list) or not raw_frames:
        raise LabelError(f"{path}: frames must be a non-empty list")
    frames = tuple(_frame(f"{path}: frame {i}", raw, beams) for i, raw in enumerate(raw_frames))
    seen: set[int] = set()
    for i, frame in enumerate(frames):
        if frame.scan in seen:
            raise LabelError(f"{path}: frame {i}: scan {frame.scan} is labelled twice")
        seen.add(frame.scan)
    if valid is not None:
        for i, frame in enumerate(frames):
            where = f"{path}: frame {i} (scan {frame.scan})"
            if frame.scan >= len(valid):
                raise LabelError(f"{where}: the log has only {len(valid)} scans")
            mask = np.asarray(valid[frame.scan], dtype=bool)
            if mask.shape != (beams,):
                raise LabelError(f"{where}: the log's scan has {mask.size} beams, the file {beams}")
            for key in _INDEX_KEYS:
                bad = [b for b in getattr(frame, key) if not mask[b]]
                if bad:
                    raise LabelError(f"{where}: {key}: beam(s) {bad} have no return in the log")
    return LabelSet(
        source=doc["source"],
        beams=beams,
        angle_convention=doc["angle_convention"],
        how_chosen=doc["how_chosen"],
        rule=doc["rule"],
        labeller=doc["labeller"],
        frames=frames,
    )


LABEL_FILES = {
    "intel": "intel_labels.json",
    "freiburg": "fr079_labels.json",
    "urg": "urg_labels.json",
}
"""Shipped sample (:data:`scanlines.data.SAMPLES`) -> its label file in this package."""


def labelled_samples() -> tuple[str, ...]:
    """The shipped samples that have hand labels installed."""
    return tuple(name for name, file in LABEL_FILES.items() if (_HERE / file).exists())


@cache
def label_set(name: str) -> LabelSet:
    """The labels of shipped sample ``name``, validated against the log (read once, cached)."""
    from scanlines.data import SAMPLES, sample
    from scanlines.io import open_log

    if name not in LABEL_FILES:
        known = ", ".join(repr(n) for n in LABEL_FILES)
        raise LabelError(f"no hand labels for sample {name!r}; labelled samples: {known}")
    path = _HERE / LABEL_FILES[name]
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise LabelError(f"{path}: cannot read label file: {exc}") from exc
    source = doc.get("source") if isinstance(doc, Mapping) else None
    if source != SAMPLES[name]:
        raise LabelError(f"{path}: source is {source!r}, expected {SAMPLES[name]!r}")
    options = label_log_options(name, doc.get("angle_convention", "step"))
    valid = [scan.valid for scan in open_log(sample(name), **options)]
    return read_labels(path, valid)


def label_log_options(name: str, angle_convention: str) -> dict[str, Any]:
    """The ``open_log`` options that read sample ``name`` with the bearings it was labelled
    with (CARMEN logs take the label file's ``angle_convention``; other readers no option)."""
    from scanlines.data import SAMPLES

    carmen = SAMPLES[name].endswith((".clf.gz", ".log.gz"))
    return {"angle_convention": angle_convention} if carmen else {}


def intel_label_set() -> LabelSet:
    """The Intel excerpt's labels (:func:`label_set`)."""
    return label_set("intel")


def intel_labels() -> list[LabelledFrame]:
    """The hand-labelled frames of the Intel excerpt, in file order (by scan index)."""
    return list(intel_label_set().frames)


def intel_label_rule() -> str:
    """The labelling rule, as written in the label file."""
    return intel_label_set().rule
