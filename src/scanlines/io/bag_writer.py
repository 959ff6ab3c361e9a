"""Writing extraction results as a ROS 2 bag directory or a single ``.mcap`` file.

The layout (topics, message types, markers, frames) is in :mod:`scanlines.io.writers`;
:func:`scanlines.io.open_writer` picks this writer for ``*.mcap`` and paths without a
suffix.
"""

from __future__ import annotations

import contextlib
import functools
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np
import orjson

from scanlines.errors import ParameterError
from scanlines.extraction import END_X, END_Y, START_X, START_Y, ExtractionTable
from scanlines.io.feature_messages import register_feature_messages
from scanlines.io.writers import (
    UNSTAMPED_PERIOD,
    Frame,
    ResultWriter,
    ScanFeatures,
    json_record,
    json_records,
)
from scanlines.outputs import OutputError, discard, temp_path
from scanlines.scan import Scan

#: Largest ``builtin_interfaces/msg/Time.sec`` (an int32).
MAX_STAMP_SECONDS = 2**31 - 1

FEATURES_TOPIC = "/scanlines/features"
"""Topic of each scan's features as its JSON Lines record (``std_msgs/msg/String``)."""

SCAN_FEATURES_TOPIC = "/scanlines/scan_features"
"""Topic of each scan's features as the typed ``scanlines/msg/ScanFeatures``
(:mod:`scanlines.io.feature_messages`; the definition is in the bag, the MCAP schema)."""

__all__ = ["Ros2BagWriter"]


_COLORS = {
    "segments": (0.1, 0.8, 0.2, 1.0),
    "breakpoints": (0.9, 0.1, 0.1, 1.0),
    "corners": (0.1, 0.3, 1.0, 1.0),
}
_SCALES = {"segments": 0.03, "breakpoints": 0.08, "corners": 0.12}


class Ros2BagWriter(ResultWriter):
    """Scans and feature markers as a ROS 2 bag directory or a single ``.mcap`` file.

    Parameters
    ----------
    path:
        ``*.mcap`` (one MCAP file) or a directory path (a ROS 2 bag).
    meta, frame:
        See :class:`ResultWriter`.
    storage:
        ``"mcap"`` (default) or ``"sqlite3"``, for a bag directory.
    topic:
        Topic of the ``LaserScan`` messages.
    markers_topic:
        Topic of the ``MarkerArray`` messages.
    laser_frame, world_frame:
        ``frame_id`` of the scans and of world-frame markers.
    overwrite:
        Replace an existing output (a directory only if it is a ROS 2 bag) and its
        ``.meta.json``.
    """

    format_name = "ros2"

    def __init__(
        self,
        path: str | Path,
        *,
        meta: Mapping[str, Any] | None = None,
        frame: Frame = "sensor",
        storage: Literal["mcap", "sqlite3"] = "mcap",
        topic: str = "/scan",
        markers_topic: str = "/scanlines/markers",
        laser_frame: str = "laser",
        world_frame: str = "map",
        overwrite: bool = False,
    ) -> None:
        super().__init__(path, meta=meta, frame=frame, overwrite=overwrite)
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore

        self.single_file = self.path.suffix.lower() == ".mcap"
        if self.single_file:
            storage = "mcap"
        if storage not in ("mcap", "sqlite3"):
            raise ParameterError(f"storage must be 'mcap' or 'sqlite3', got {storage!r}")
        self._check_target()
        self.storage = storage
        self.topic = topic
        self.laser_frame = laser_frame
        self.marker_frame = world_frame if frame == "world" else laser_frame
        self.world_frame = world_frame
        self._types = get_typestore(Stores.ROS2_HUMBLE)
        register_feature_messages(self._types)
        self._tmpdir = temp_path(self.path)
        with self._naming_the_output():  # a read-only folder, say
            self._tmpdir.mkdir()
        self._bag_dir = self._tmpdir / (self.path.stem if self.single_file else self.path.name)
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        self._writer = Writer(self._bag_dir, version=8, storage_plugin=plugin)
        try:
            self._writer.open()
            add = self._writer.add_connection
            self._scan_conn = add(topic, "sensor_msgs/msg/LaserScan", typestore=self._types)
            self._marker_conn = add(
                markers_topic, "visualization_msgs/msg/MarkerArray", typestore=self._types
            )
            self._tf_conn = add("/tf", "tf2_msgs/msg/TFMessage", typestore=self._types)
            self._features_conn = add(FEATURES_TOPIC, "std_msgs/msg/String", typestore=self._types)
            self._typed_conn = add(
                SCAN_FEATURES_TOPIC, "scanlines/msg/ScanFeatures", typestore=self._types
            )
        except BaseException:
            self._abort()
            raise

    def _check_target(self) -> None:
        if not self.path.exists():
            return
        if self.single_file == self.path.is_dir():
            wanted = "an .mcap file" if self.single_file else "a bag directory"
            raise ParameterError(f"{self.path} exists and is not {wanted}; not replacing it")
        if self.path.is_dir() and not (self.path / "metadata.yaml").exists():
            raise ParameterError(
                f"{self.path} is a directory that is not a ROS 2 bag; not replacing it"
            )

    # -- message construction -------------------------------------------------------------

    def _stamp(self, features: ScanFeatures) -> tuple[Any, int]:
        seconds = features.scan.timestamp
        if seconds is None or not math.isfinite(seconds) or seconds < 0:
            seconds = features.index * UNSTAMPED_PERIOD
        sec = math.floor(seconds)
        nanosec = round((seconds - sec) * 1e9)
        if nanosec >= 1_000_000_000:
            sec, nanosec = sec + 1, nanosec - 1_000_000_000
        if sec > MAX_STAMP_SECONDS:
            raise OutputError(
                f"{self.path}: scan {features.index} has timestamp {seconds!r} s, past what a "
                f"ROS 2 stamp holds (int32 seconds, at most {MAX_STAMP_SECONDS}: January 2038); "
                "write .jsonl or .csv instead, or shift the log's times"
            )
        time = self._types.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
        return time, sec * 1_000_000_000 + nanosec

    def _header(self, stamp: Any, frame_id: str) -> Any:
        return self._types.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)

    def _laser_scan(self, scan: Scan, stamp: Any) -> Any:
        n = len(scan)
        intensities = scan.intensities if scan.intensities is not None else np.empty(0)
        return self._types.types["sensor_msgs/msg/LaserScan"](
            header=self._header(stamp, self.laser_frame),
            angle_min=scan.angle_min,
            angle_max=scan.angle_min + (n - 1) * scan.angle_increment,
            angle_increment=scan.angle_increment,
            time_increment=0.0,
            scan_time=0.0,
            range_min=float(_as_float32(scan.range_min)),
            range_max=float(_as_float32(scan.range_max)),
            ranges=_as_float32(scan.ranges),
            intensities=_as_float32(intensities),
        )

    def _marker(self, stamp: Any, namespace: str, marker_id: int, points: np.ndarray) -> Any:
        t = self._types.types
        header = self._header(stamp, self.marker_frame)
        point = t["geometry_msgs/msg/Point"]
        return t["visualization_msgs/msg/Marker"](
            header=header,
            ns=namespace,
            id=marker_id,
            points=[point(x=x, y=y, z=0.0) for x, y in points.tolist()],
            texture=t["sensor_msgs/msg/CompressedImage"](
                header=header, format="", data=np.empty(0, dtype=np.uint8)
            ),
            **self._marker_constants(namespace),
        )

    @functools.cache  # noqa: B019 - one writer, a handful of namespaces
    def _marker_constants(self, namespace: str) -> dict[str, Any]:
        """The fields of a marker that depend on its namespace alone (read-only, shared)."""
        t = self._types.types
        marker_type = t["visualization_msgs/msg/Marker"]
        if namespace == "":
            kind, action, scale, color = (
                marker_type.SPHERE_LIST,
                marker_type.DELETEALL,
                1.0,
                (0,) * 4,
            )
        else:
            kind = marker_type.LINE_LIST if namespace == "segments" else marker_type.SPHERE_LIST
            action, scale, color = marker_type.ADD, _SCALES[namespace], _COLORS[namespace]
        return {
            "type": kind,
            "action": action,
            "pose": t["geometry_msgs/msg/Pose"](
                position=t["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
                orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            ),
            "scale": t["geometry_msgs/msg/Vector3"](x=scale, y=scale, z=scale),
            "color": t["std_msgs/msg/ColorRGBA"](r=color[0], g=color[1], b=color[2], a=color[3]),
            "lifetime": t["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
            "frame_locked": False,
            "colors": [],
            "texture_resource": "",
            "uv_coordinates": [],
            "text": "",
            "mesh_resource": "",
            "mesh_file": t["visualization_msgs/msg/MeshFile"](
                filename="", data=np.empty(0, dtype=np.uint8)
            ),
            "mesh_use_embedded_materials": False,
        }

    def _markers(self, features: ScanFeatures, stamp: Any) -> Any:
        lines = features.extraction.lines
        segment_points = lines[:, [START_X, START_Y, END_X, END_Y]].reshape(-1, 2)
        groups = (
            ("segments", segment_points),
            ("breakpoints", features.breakpoint_points),
            ("corners", features.corner_points),
        )
        markers = [self._marker(stamp, "", 0, np.empty((0, 2)))]
        markers += [
            self._marker(stamp, name, 0, points) for name, points in groups if len(points) > 0
        ]
        return self._types.types["visualization_msgs/msg/MarkerArray"](markers=markers)

    def _scan_features(self, features: ScanFeatures, stamp: Any) -> Any:
        t = self._types.types
        extraction = features.extraction
        lines = extraction.lines.astype(np.float32)
        covariances = extraction.covariances.astype(np.float32).reshape(-1, 4)
        segment = t["scanlines/msg/Segment"]
        segments = [
            segment(
                first=int(first), last=int(last), n_points=int(n), radius=float(row[0]),
                angle=float(row[1]), covariance=covariance,
                start=row[[START_X, START_Y]], end=row[[END_X, END_Y]], rms=float(row[6]),
                start_kind=int(kinds[0]), end_kind=int(kinds[1]),
            )
            for first, last, n, row, covariance, kinds in zip(
                extraction.first.tolist(), extraction.last.tolist(),
                extraction.n_points.tolist(), lines, covariances,
                extraction.end_kinds.tolist(), strict=True,
            )
        ]  # fmt: skip
        point = t["geometry_msgs/msg/Point"]

        def points(xy: np.ndarray) -> list[Any]:
            return [point(x=x, y=y, z=0.0) for x, y in xy.tolist()]

        def beams(values: np.ndarray) -> np.ndarray:
            return np.asarray(values, dtype=np.int32)

        return t["scanlines/msg/ScanFeatures"](
            header=self._header(stamp, self.marker_frame),
            method=extraction.method,
            segments=segments,
            breakpoints=beams(extraction.breakpoints),
            corners=beams(extraction.corners),
            outliers=beams(extraction.outliers),
            breakpoint_points=points(features.breakpoint_points),
            corner_points=points(features.corner_points),
        )

    def _transform(self, pose: Sequence[float], stamp: Any) -> Any:
        t = self._types.types
        x, y, theta = pose
        transform = t["geometry_msgs/msg/TransformStamped"](
            header=self._header(stamp, self.world_frame),
            child_frame_id=self.laser_frame,
            transform=t["geometry_msgs/msg/Transform"](
                translation=t["geometry_msgs/msg/Vector3"](x=x, y=y, z=0.0),
                rotation=t["geometry_msgs/msg/Quaternion"](
                    x=0.0, y=0.0, z=math.sin(theta / 2.0), w=math.cos(theta / 2.0)
                ),
            ),
        )
        return t["tf2_msgs/msg/TFMessage"](transforms=[transform])

    # -- hooks ----------------------------------------------------------------------------

    def _write(self, features: ScanFeatures) -> None:
        self._write_encoded(self._messages(features, json_record(features)))

    def encode_chunk(self, indices, scans, table) -> list[tuple[Any, int, bytes]]:
        """Every message of a chunk, serialised (the features records of the chunk are
        encoded at once)."""
        features = [
            ScanFeatures(i, s, e, self.frame) for i, s, e in zip(indices, scans, table, strict=True)
        ]
        if self.frame == "world":
            table = ExtractionTable.concatenate(
                [f.extraction for f in features], table.method, table.params
            )
        records = json_records(indices, scans, table, self.frame)
        return [
            message
            for scan_features, record in zip(features, records, strict=True)
            for message in self._messages(scan_features, orjson.dumps(record).decode())
        ]

    def _write_encoded(self, messages: list[tuple[Any, int, bytes]]) -> None:
        for connection, bag_time, data in messages:
            self._writer.write(connection, bag_time, data)

    def _messages(self, features: ScanFeatures, record: str) -> list[tuple[Any, int, bytes]]:
        """The serialised messages of one scan (its features record given as JSON)."""
        stamp, bag_time = self._stamp(features)
        serialize = self._types.serialize_cdr
        scan_msg = self._laser_scan(features.scan, stamp)
        markers = self._markers(features, stamp)
        text = self._types.types["std_msgs/msg/String"](data=record)
        messages = [
            (self._scan_conn, serialize(scan_msg, "sensor_msgs/msg/LaserScan")),
            (self._marker_conn, serialize(markers, "visualization_msgs/msg/MarkerArray")),
            (self._features_conn, serialize(text, "std_msgs/msg/String")),
            (
                self._typed_conn,
                serialize(self._scan_features(features, stamp), "scanlines/msg/ScanFeatures"),
            ),
        ]
        if features.scan.pose is not None:
            tf = self._transform(features.scan.pose, stamp)
            messages.append((self._tf_conn, serialize(tf, "tf2_msgs/msg/TFMessage")))
        return [(connection, bag_time, data) for connection, data in messages]

    @property
    def _temporary(self) -> Path:
        if self.single_file:
            return self._bag_dir / f"{self._bag_dir.name}.mcap"
        return self._bag_dir

    def _finish(self) -> None:
        self._writer.close()

    def _abort(self) -> None:
        with contextlib.suppress(Exception):
            self._writer.abort()
        discard(self._tmpdir)

    def close(self) -> None:
        """Finish the bag and move it into place with its ``.meta.json``."""
        try:
            super().close()
        finally:
            discard(self._tmpdir)


def _as_float32(values: Any) -> np.ndarray:
    """Values as float32, as a LaserScan holds them (beyond float32's range: infinite)."""
    with np.errstate(over="ignore"):
        return np.asarray(values, dtype=np.float32)
