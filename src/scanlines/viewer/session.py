"""What the viewer shows, computed through the library: a scan's features under one or two
configurations (with their differences), a stretch of the log in the world frame, the
log's line map, and the methods with their parameter domains.

A configuration is ``{"method": ..., "preset": ..., "params": {...}}`` (the parameters the
user changed; :class:`scanlines.config.ExtractionConfig`). Scans are extracted as
``scanlines run`` extracts them: with the sensor profile given, else the one measured from
the log's first scans.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from collections.abc import Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from scanlines.config import ExtractionConfig
from scanlines.errors import ParameterError, ScanlinesError, one_line
from scanlines.viewer.scan_store import ScanStore

if TYPE_CHECKING:  # the extraction modules: imported on first use, so that the page is
    # served (and the first scan's returns drawn) while they load
    from scanlines.extractor import Extractor
    from scanlines.scan import Scan
    from scanlines.sensor.profile import SensorProfile

__all__ = ["MAX_WORLD_SCANS", "NoPoses", "ViewerSession", "methods"]

#: Most scans a world view extracts (a longer stretch is sampled evenly).
MAX_WORLD_SCANS = 600
_CACHED_EXTRACTORS = 16


class NoPoses(ParameterError):
    """A view that needs the log's poses, asked of a log without them (HTTP 409)."""

    status = 409


def methods() -> list[dict[str, Any]]:
    """Every method with its parameters (default, doc, allowed values, domain, and when
    another parameter decides whether it is read: ``applies``) and presets: what the viewer
    builds its controls from."""
    from scanlines.extractor import method_info, method_names

    described = []
    for name in method_names():
        info = method_info(name)
        params = [
            {"name": key, "default": p.default, "doc": p.doc, "allowed": p.allowed,
             "domain": p.domain, "applies": _applies(p.applies)}
            for key, p in info.params.items()
        ]  # fmt: skip
        described.append({"name": name, "doc": info.doc, "params": params,
                          "presets": info.presets})  # fmt: skip
    return described


def _applies(rule) -> dict[str, Any] | None:
    """``{"param", "values", "when_in"}`` of a parameter's ``applies``; ``None``: always read."""
    if rule is None:
        return None
    return {"param": rule[0], "values": list(rule[1]), "when_in": rule[2]}


class ViewerSession:
    """A log open in the viewer.

    Parameters
    ----------
    store:
        The log's scans.
    sensor_profile:
        The profile every extraction takes; ``None``: measured from the log's first
        scans when first needed, as ``scanlines run`` measures it
        (:func:`scanlines.runs.runner.log_profile`).
    config:
        The configuration the page opens with (default: the default method).
    config_later:
        The configuration is given later, by :meth:`configure` (``scanlines view`` serves
        the page while it checks the configuration); what needs it waits for it.
    """

    def __init__(
        self, store: ScanStore, sensor_profile: SensorProfile | None = None,
        config: ExtractionConfig | None = None, *, config_later: bool = False,
    ) -> None:  # fmt: skip
        self.store = store
        self._config = config
        self._configured = threading.Event()
        if not config_later:
            self.configure(config or ExtractionConfig())
        self._profile = sensor_profile
        self._profile_note = "given" if sensor_profile is not None else None
        self._profile_lock = threading.Lock()
        self._extractors: OrderedDict[str, Extractor] = OrderedDict()
        self._extractors_lock = threading.Lock()
        self.first_frame = threading.Event()
        """Set once a frame has been served (background work may wait for it)."""
        self._prepare_lock = threading.Lock()
        self._map: tuple[str, dict[str, Any]] | None = None  # (configuration key, the map)
        self._map_lock = threading.Lock()
        self.ready = threading.Event()
        """Set once the first configuration's kernels are loaded and the profile measured
        (:meth:`prepare`); the page says it is preparing until then."""

    @property
    def config(self) -> ExtractionConfig:
        """The configuration the page opens with (waits for :meth:`configure`).

        Raises
        ------
        ParameterError
            If the configuration was refused (:meth:`refuse`).
        """
        self._configured.wait()
        if self._config is None:
            raise ParameterError("the viewer's configuration was refused")
        return self._config

    def configure(self, config: ExtractionConfig) -> None:
        """Set the configuration the page opens with."""
        self._config = config
        self._configured.set()

    def refuse(self) -> None:
        """The configuration given later was not valid: what waits for it fails."""
        self._config = None
        self._configured.set()

    # -- the log --------------------------------------------------------------------------

    def log(self) -> dict[str, Any]:
        """The log's name, format, scans read so far, poses, reading state and profile."""
        store = self.store
        return {
            "path": str(store.path), "name": store.path.name, "format": store.format_name,
            "scans": store.count, "finished": store.finished, "error": store.error,
            "poses": store.with_pose, "reader": store.reader_info if store.finished else {},
            "poses_note": poses_note(store.reader_info) if store.with_pose else None,
            "profile": self._profile_note, "profile_noise": self._profile_noise(),
            "config": self.config.to_dict(),
            "ready": self.ready.is_set(),
        }  # fmt: skip

    def prepare(self) -> None:
        """Measure the profile and load the first configuration's kernels (by extracting
        the first scan), then let the log be read on (see :meth:`ScanStore.hold`). Once:
        a second call waits for the first."""
        with self._prepare_lock:
            if self.ready.is_set():
                return
            try:
                self.extractor(self.config.to_dict())(self.store.scan(0))
            finally:
                self.ready.set()
                self.store.resume()

    def _profile_noise(self) -> dict[str, float] | None:
        """The measured or given profile's noise (as a frame's ``noise``), once known."""
        profile = self._profile if self._profile_note is not None else None
        if profile is None:
            return None
        return profile.noise._asdict()

    def profile(self) -> SensorProfile | None:
        """The sensor profile of the extractions (measured once, on first use)."""
        with self._profile_lock:
            if self._profile_note is None:
                self._profile, self._profile_note = self._measure_profile()
            return self._profile

    def _measure_profile(self) -> tuple[SensorProfile | None, str]:
        # From the log itself, as `scanlines run` measures it (not from the store's
        # float32 copy): the same profile, so the same features as a run.
        from scanlines.runs.runner import log_profile

        try:
            profile = log_profile(self.store.path, self.store.reader_options)
        except ScanlinesError as error:  # too few returns, or a malformed record among them
            return None, f"not measured ({one_line(str(error))}): each scan's noise is its own"
        return profile, (
            f"measured from the first {profile.scans} scans: noise "
            f"{1000 * profile.noise_sigma0:.1f} mm + {100 * profile.noise_per_metre:.2f} % of range"
        )

    # -- extraction -----------------------------------------------------------------------

    def extractor(self, config: Mapping[str, Any]) -> Extractor:
        """The extractor of a configuration (checked: a bad one is a ParameterError)."""
        checked = ExtractionConfig.from_dict(config, source="configuration")
        key = repr((checked.method, checked.preset, sorted(checked.params.items())))
        with self._extractors_lock:
            extractor = self._extractors.get(key)
            if extractor is not None:
                self._extractors.move_to_end(key)
                return extractor
        from scanlines.extractor import Extractor

        profile = self.profile()
        extractor = Extractor(
            checked.method, checked.preset, sensor_profile=profile, **checked.params
        )
        with self._extractors_lock:
            self._extractors[key] = extractor
            while len(self._extractors) > _CACHED_EXTRACTORS:
                self._extractors.popitem(last=False)
        return extractor

    def frame(self, index: int, configs: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
        """Scan ``index`` and its features under each of ``configs`` (one or two; none: the
        scan alone, which needs no kernel, for the page to draw while they load)."""
        if len(configs) > 2:
            raise ParameterError(f"a frame takes one or two configurations, got {len(configs)}")
        extractors = [self.extractor(config) for config in configs]
        scan = self.store.scan(index)
        results = [_result(extractor, scan) for extractor in extractors]
        if len(results) == 2:
            _mark_differences(*results)
        noise = _noise(scan) if results else None
        points = scan.points
        if results:
            self.first_frame.set()
        return {
            "index": index, "record": self.store.record(index), "timestamp": scan.timestamp,
            "pose": scan.pose, "beams": len(scan), "returns": int(scan.valid.sum()),
            "x": points[:, 0], "y": points[:, 1], "noise": noise, "results": results,
        }  # fmt: skip

    def world(self, first: int, last: int, config: Mapping[str, Any]) -> dict[str, Any]:
        """Scans ``first..last`` (at most :data:`MAX_WORLD_SCANS`, evenly sampled) in the
        world frame: their segments, a sample of their returns, and the sensor's path."""
        self.store.wait_for(1)
        if not self.store.with_pose:
            raise ParameterError(f"{self.store.path.name} has no poses: no world view")
        if first < 0 or last < first:
            raise ParameterError(f"world view takes 0 <= first <= last, got {first}..{last}")
        from scanlines.geometry.transform import points_to_world, to_world

        extractor = self.extractor(config)
        self.store.scan(last)  # waits for it; out of range is an error naming the log
        indices = np.unique(np.linspace(first, last, min(last - first + 1, MAX_WORLD_SCANS)))
        segments, xs, ys, path = [], [], [], []
        for index in indices.astype(int).tolist():
            scan = self.store.scan(index)
            world = to_world(extractor(scan), scan.pose)
            segments.append(world.lines[:, 2:6])
            returns = scan.points[scan.valid][:: max(1, len(scan) // 180)]
            moved = points_to_world(returns, scan.pose)
            xs.append(moved[:, 0])
            ys.append(moved[:, 1])
            path.append(scan.pose)
        return {
            "first": first, "last": last, "scans": len(indices),
            "segments": np.concatenate(segments) if segments else np.zeros((0, 4)),
            "x": np.concatenate(xs), "y": np.concatenate(ys), "path": np.array(path),
        }  # fmt: skip

    # -- the line map ---------------------------------------------------------------------

    def line_map(self, config: Mapping[str, Any]) -> dict[str, Any]:
        """The line map of the whole log (:func:`scanlines.map.build_map`, as ``scanlines
        map`` builds it: the log's poses, the default fusion settings) under ``config``:
        built on first request and kept; built again only for another configuration.

        Raises
        ------
        NoPoses
            If the log's scans carry no poses.
        """
        checked = ExtractionConfig.from_dict(config, source="configuration")
        key = repr((checked.method, checked.preset, sorted(checked.params.items())))
        with self._map_lock:
            if self._map is None or self._map[0] != key:
                self._map = key, self._build_map(checked)
            return self._map[1]

    def _build_map(self, config: ExtractionConfig) -> dict[str, Any]:
        from scanlines.map import build_map
        from scanlines.map.export import map_records

        self.store.wait_for(1)
        if not self.store.with_pose:
            raise NoPoses(f"{self.store.path.name} has no poses: no line map")
        extractor = self.extractor(config.to_dict())
        started = time.perf_counter()
        build = build_map(self._every_scan(), extractor, source=self.store.path.name)
        lines = build.line_map.lines()
        return {
            "config": config.to_dict(), "poses": build.poses, "poses_note": build.pose_note,
            "origin": list(lines.origin), "scans": build.scans, "segments": build.segments,
            "seconds": time.perf_counter() - started, "lines": map_records(lines),
        }  # fmt: skip

    def _every_scan(self) -> Iterator[tuple[int, Scan]]:
        """``(index, scan)`` of every scan of the log, read to its end."""
        self.store.resume()
        self.store.wait_for(10**12)
        for index in range(self.store.count):
            yield index, self.store.scan(index)


def _result(extractor: Extractor, scan: Scan) -> dict[str, Any]:
    started = time.perf_counter()
    extraction = extractor(scan)
    milliseconds = 1000 * (time.perf_counter() - started)
    return {
        "method": extractor.method, "preset": extractor.preset,
        "segments": extraction.to_dict()["segments"],
        "breakpoints": extraction.breakpoints, "corners": extraction.corners,
        "outliers": extraction.outliers, "extract_ms": milliseconds,
    }  # fmt: skip


def _noise(scan: Scan) -> dict[str, float]:
    from scanlines.sensor.profile import scan_noise_line

    return scan_noise_line(scan)._asdict()


def _mark_differences(a: dict[str, Any], b: dict[str, Any]) -> None:
    """Mark, in each result, the segments (by beam span) and events the other lacks."""
    for mine, theirs in ((a, b), (b, a)):
        spans = {(s["first"], s["last"]) for s in theirs["segments"]}
        mine["differing_segments"] = [
            k for k, s in enumerate(mine["segments"]) if (s["first"], s["last"]) not in spans
        ]
        for events in ("breakpoints", "corners"):
            other = set(np.asarray(theirs[events]).tolist())
            mine[f"differing_{events}"] = [
                int(beam) for beam in np.asarray(mine[events]).tolist() if beam not in other
            ]


def poses_note(reader_info: dict[str, Any]) -> str:
    """Which poses the world view draws, as far as the reader says: raw odometry when the
    log's records are known to hold it, else the poses as the log records them (a
    CARMEN ``FLASER`` or a bag cannot tell corrected poses from odometry)."""
    message = str(reader_info.get("message") or "")
    keys = reader_info.get("keys") or []
    if message.startswith("RAWLASER"):
        return "poses: raw odometry (the log's ODOM records)"
    if "odom_pose" in keys:
        return "poses: raw odometry (the file's odom_pose)"
    return "poses as recorded in the log (may be raw odometry)"
