"""One scan's features in the output frame, and the JSON Lines and CSV records of a chunk."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property
from typing import Any, Literal

import numpy as np
import orjson

from scanlines.errors import ParameterError
from scanlines.extraction import (
    ALPHA,
    END_KINDS,
    END_X,
    END_Y,
    RHO,
    RMS,
    START_X,
    START_Y,
    Extraction,
    ExtractionTable,
)
from scanlines.geometry.transform import points_to_world, to_world
from scanlines.scan import Scan

Frame = Literal["sensor", "world"]

#: Columns of the CSV output, in order.
CSV_COLUMNS = (
    "scan",
    "timestamp",
    "first",
    "last",
    "start_x",
    "start_y",
    "end_x",
    "end_y",
    "rho",
    "alpha",
    "n_points",
    "rms",
    "var_rho",
    "cov_rho_alpha",
    "var_alpha",
    "start_kind",
    "end_kind",
    "pose_x",
    "pose_y",
    "pose_theta",
    "feature",
    "beam",
    "x",
    "y",
)


class ScanFeatures:
    """What a writer needs from one scan, in the output frame.

    Attributes
    ----------
    index, scan:
        Record index in the log and the scan itself.
    extraction:
        Features, transformed to the output frame.
    breakpoint_points, corner_points, outlier_points, return_points:
        ``K x 2`` positions of the breakpoint, corner and outlier beams and of every
        beam with a return, in the output frame (computed on first access: only the
        bag and Rerun writers draw them).
    """

    def __init__(self, index: int, scan: Scan, extraction: Extraction, frame: Frame) -> None:
        if frame == "world" and scan.pose is None:
            raise ParameterError(
                f"frame='world' needs scan poses, but scan {index} has none; use frame='sensor'"
            )
        self.index, self.scan, self.frame = index, scan, frame
        self.extraction = extraction if frame == "sensor" else to_world(extraction, scan.pose)
        self._sensor_extraction = extraction

    @cached_property
    def breakpoint_points(self) -> np.ndarray:
        return self._points(self._sensor_extraction.breakpoints)

    @cached_property
    def corner_points(self) -> np.ndarray:
        return self._points(self._sensor_extraction.corners)

    @cached_property
    def outlier_points(self) -> np.ndarray:
        return self._points(self._sensor_extraction.outliers)

    @cached_property
    def return_points(self) -> np.ndarray:
        return self._points(np.flatnonzero(self.scan.valid))

    def _points(self, beams: np.ndarray) -> np.ndarray:
        points = _beam_points(self.scan, beams)
        return points if self.frame == "sensor" else points_to_world(points, self.scan.pose)


def beam_xy(scan: Scan, beams: np.ndarray, frame: Frame = "sensor") -> np.ndarray:
    """``K x 2`` positions of the beams ``beams`` (a breakpoint or corner list), aligned
    with it: NaN for a beam without a return; in the world frame with ``frame="world"``."""
    beams = np.asarray(beams, dtype=np.intp)
    points = np.full((len(beams), 2), np.nan)
    inside = (beams >= 0) & (beams < len(scan))
    chosen = beams[inside]
    r = np.where(scan.valid[chosen], scan.ranges[chosen], np.nan)
    angles = scan.angle_min + scan.angle_increment * chosen.astype(np.float64)
    points[inside] = np.column_stack((r * np.cos(angles), r * np.sin(angles)))
    if frame == "world" and scan.pose is not None:
        points = points_to_world(points, scan.pose)
    return points


def _beam_points(scan: Scan, indices: np.ndarray) -> np.ndarray:
    """Points of the beams ``indices`` that have a return (rows of ``scan.points``)."""
    indices = np.asarray(indices, dtype=np.intp)
    inside = indices[(indices >= 0) & (indices < len(scan))]
    beams = inside[scan.valid[inside]]
    # the same arithmetic as Scan.points, for these beams only
    r = scan.ranges[beams]
    angles = scan.angle_min + scan.angle_increment * beams.astype(np.float64)
    points = np.column_stack((r * np.cos(angles), r * np.sin(angles)))
    return points[np.isfinite(points).all(axis=1)]


def json_records(
    indices: Sequence[int],
    scans: Sequence[Scan],
    table: ExtractionTable,
    frame: Frame = "sensor",
) -> list[dict[str, Any]]:
    """The JSON Lines records (:mod:`scanlines.io.writers`) of a chunk of scans and their
    features (in the output frame ``frame``); non-finite numbers are left to the encoder
    (null)."""
    lines = table.lines
    columns = (
        table.first.tolist(),
        table.last.tolist(),
        lines[:, START_X : START_Y + 1].tolist(),
        lines[:, END_X : END_Y + 1].tolist(),
        lines[:, RHO].tolist(),
        lines[:, ALPHA].tolist(),
        table.n_points.tolist(),
        lines[:, RMS].tolist(),
        table.covariances.tolist(),
        [END_KINDS[kind] for kind in table.end_kinds[:, 0].tolist()],
        [END_KINDS[kind] for kind in table.end_kinds[:, 1].tolist()],
    )
    every_segment = [
        {
            "first": first,
            "last": last,
            "start": start,
            "end": end,
            "rho": rho,
            "alpha": alpha,
            "n_points": n_points,
            "rms": rms,
            "covariance": covariance,
            "start_kind": start_kind,
            "end_kind": end_kind,
        }
        for (
            first,
            last,
            start,
            end,
            rho,
            alpha,
            n_points,
            rms,
            covariance,
            start_kind,
            end_kind,
        ) in zip(*columns, strict=True)
    ]
    segment_offsets = table.offsets["segments"].tolist()
    breakpoints, breakpoint_offsets = table.breakpoints.tolist(), table.offsets["breakpoints"]
    corners, corner_offsets = table.corners.tolist(), table.offsets["corners"]
    records = []
    for k, (index, scan) in enumerate(zip(indices, scans, strict=True)):
        segments = every_segment[segment_offsets[k] : segment_offsets[k + 1]]
        scan_breakpoints = breakpoints[breakpoint_offsets[k] : breakpoint_offsets[k + 1]]
        scan_corners = corners[corner_offsets[k] : corner_offsets[k + 1]]
        records.append(
            {
                "scan": int(index),
                "timestamp": scan.timestamp,
                "pose": None if scan.pose is None else [float(v) for v in scan.pose],
                "segments": segments,
                "breakpoints": scan_breakpoints,
                "corners": scan_corners,
                "breakpoint_xy": beam_xy(scan, scan_breakpoints, frame).tolist(),
                "corner_xy": beam_xy(scan, scan_corners, frame).tolist(),
            }
        )
    return records


def encode_json_lines(
    indices: Sequence[int], scans: Sequence[Scan], table: ExtractionTable, frame: Frame = "sensor"
) -> bytes:
    """The JSON Lines text of a chunk (:func:`json_records`), UTF-8, one line per scan.

    orjson writes NaN and infinities as ``null`` and each float in its shortest
    round-trip form."""
    records = json_records(indices, scans, table, frame)
    return b"".join(orjson.dumps(r) + b"\n" for r in records)


def json_record(features: ScanFeatures) -> str:
    """The JSON Lines record of one scan (:mod:`scanlines.io.writers`), without the newline."""
    extraction = features.extraction
    table = ExtractionTable.concatenate([extraction], extraction.method, extraction.params)
    records = json_records([features.index], [features.scan], table, features.frame)
    return orjson.dumps(records[0]).decode()


def encode_csv_rows(
    indices: Sequence[int], scans: Sequence[Scan], table: ExtractionTable, frame: Frame = "sensor"
) -> bytes:
    """The CSV rows (:data:`CSV_COLUMNS`) of a chunk, UTF-8: per scan, one row per
    segment (``feature`` ``segment``), then one per breakpoint and per corner (``beam``,
    ``x``, ``y``, the segment cells empty); numbers as in JSON Lines, empty cells for
    missing or non-finite values; the scan's pose on every row."""
    numbers = np.column_stack(
        (
            table.lines[:, [START_X, START_Y, END_X, END_Y, RHO, ALPHA]],
            table.n_points,
            table.lines[:, RMS],
            table.covariances.reshape(-1, 4)[:, [0, 1, 3]],
        )
    ).tolist()
    stamps = [scan.timestamp for scan in scans]
    first, last, n_points = table.first.tolist(), table.last.tolist(), table.n_points.tolist()
    kinds = [f"{END_KINDS[a]},{END_KINDS[b]}".encode() for a, b in table.end_kinds.tolist()]
    segment_offsets = table.offsets["segments"].tolist()
    no_segment = b"," * 14  # first .. end_kind, empty
    rows = []
    for k, scan in enumerate(scans):
        pose = list(scan.pose) if scan.pose is not None else [None] * 3
        tail = orjson.dumps(pose)[1:-1]
        for j in range(segment_offsets[k], segment_offsets[k + 1]):
            values = numbers[j]
            values[6] = n_points[j]
            cells = orjson.dumps([indices[k], stamps[k], first[j], last[j], *values])[1:-1]
            rows.append(cells + b"," + kinds[j] + b"," + tail + b",segment,,,\n")
        head = orjson.dumps([indices[k], stamps[k]])[1:-1]
        for kind in ("breakpoints", "corners"):
            start, stop = table.offsets[kind][k], table.offsets[kind][k + 1]
            beams = table.columns[kind][start:stop]
            for beam, (x, y) in zip(
                beams.tolist(), beam_xy(scan, beams, frame).tolist(), strict=True
            ):
                event = orjson.dumps([kind[:-1], beam, x, y])[1:-1].replace(b'"', b"")
                rows.append(head + b"," + no_segment + b"," + tail + b"," + event + b"\n")
    return b"".join(rows).replace(b"null", b"")
