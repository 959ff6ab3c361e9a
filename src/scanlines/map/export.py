"""A line map written as GeoJSON, SVG, DXF (ezdxf) or JSON with covariances.

Coordinates: the endpoints of GeoJSON, JSON and DXF are in the log's own world frame, in
metres (a log in UTM stays in UTM); they are not WGS84 longitudes and latitudes, and each
file says so. The SVG is drawn in metres about the map's local origin (its ``viewBox`` is
metric; the origin is written in the file), since SVG renderers draw in single precision.
``rho``, ``alpha`` and their covariance are given in the map's local frame, whose origin
every file states (:mod:`scanlines.map.frame`). No writer emits NaN or infinity: JSON
gets ``null`` where a number is missing.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ParameterError
from scanlines.map.fusion import BACK, BOTH, FRONT, MapLines
from scanlines.outputs import (
    OutputError,
    check_output,
    commit,
    discard,
    temp_path,
    write_error,
    write_text_atomically,
)
from scanlines.report import jsonable

__all__ = [
    "FRAME_NOTE",
    "MAP_FORMATS",
    "check_map_format",
    "dumps",
    "map_records",
    "naming_output",
    "write_map",
]

#: What the coordinates of a map file are.
FRAME_NOTE = (
    "metres in the log's own world frame, a local metric frame: not WGS84 longitude and "
    "latitude; a GIS must be told the frame (for a log in UTM, its zone's EPSG code)"
)


def dumps(document: Any) -> str:
    """``document`` as strict JSON (NaN as ``null``; never a bare ``NaN`` or ``Infinity``)."""
    return json.dumps(jsonable(document), indent=1, allow_nan=False) + "\n"


@contextlib.contextmanager
def naming_output(path: Path, what: str = "the map") -> Iterator[None]:
    """Turn an ``OSError`` of writing ``path`` (a full disk, a read-only folder, where the
    error names only a temporary file or nothing) into one :class:`OutputError` naming it."""
    try:
        yield
    except OutputError:
        raise
    except OSError as error:
        raise write_error(path, error, what) from None


MAP_FORMATS = (".geojson", ".json", ".svg", ".dxf")


def check_map_format(path: str | Path) -> str:
    """The writer's suffix of ``path`` (:data:`MAP_FORMATS`), or a :class:`ParameterError`
    naming the file; DXF also needs ezdxf installed."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in MAP_FORMATS:
        raise ParameterError(
            f"{path}: a map is written as {', '.join(MAP_FORMATS)}; got suffix {suffix!r}"
        )
    if suffix == ".dxf":
        _ezdxf()
    return suffix


def _ezdxf():
    try:
        import ezdxf
    except ImportError:
        raise ParameterError(
            'a DXF map needs ezdxf: pip install ".[map]" (or ".[map]" in a checkout)'
        ) from None
    return ezdxf


#: How a map file names the sides a line was seen from (``seen_from``): the side its normal
#: ``(cos alpha, sin alpha)`` points to, the other side, or both.
SIDE_NAMES = {FRONT: "normal side", BACK: "other side", BOTH: "both sides"}


def map_records(lines: MapLines) -> list[dict[str, Any]]:
    """One dict per map line: geometry (``start``, ``end`` in the world frame), estimate
    (``rho``, ``alpha`` in the map's local frame, about ``lines.origin``), covariance and
    support."""
    records = []
    start, end = lines.world_start, lines.world_end
    for k in range(len(lines)):
        records.append(
            {
                "start": [float(v) for v in start[k]],
                "end": [float(v) for v in end[k]],
                "rho": float(lines.rho[k]),
                "alpha": float(lines.alpha[k]),
                "covariance": [[float(v) for v in row] for row in lines.covariances[k]],
                "length": float(np.hypot(*(lines.end[k] - lines.start[k]))),
                "scans": int(lines.scans[k]),
                "returns": int(lines.returns[k]),
                "segments": int(lines.segments[k]),
                "first_scan": int(lines.first_scan[k]),
                "last_scan": int(lines.last_scan[k]),
                "seen_from": SIDE_NAMES[BOTH if lines.sides is None else int(lines.sides[k])],
            }
        )
    return records


def write_map(
    lines: MapLines, path: str | Path, *, meta: dict[str, Any] | None = None, overwrite: bool
) -> Path:
    """Write ``lines`` to ``path`` in the format its suffix names (:data:`MAP_FORMATS`)."""
    path = Path(path)
    suffix = check_map_format(path)
    meta = meta or {}
    if suffix == ".dxf":
        with naming_output(path):
            return _write_dxf(lines, path, meta, overwrite)
    text = {".geojson": _geojson, ".json": _json, ".svg": _svg}[suffix](lines, meta)
    with naming_output(path):
        return write_text_atomically(path, text, overwrite=overwrite)


def frame_record(lines: MapLines) -> dict[str, Any]:
    """What a map file says about its coordinates and the map's local frame."""
    return {
        "units": "metre",
        "coordinates": FRAME_NOTE,
        "origin": [float(v) for v in lines.origin],
        "local_frame": "rho, alpha and their covariance: (x - origin[0]) cos(alpha) + "
        "(y - origin[1]) sin(alpha) = rho, the frame the map was built in",
    }


def _geojson(lines: MapLines, meta: dict[str, Any]) -> str:
    features = []
    for record in map_records(lines):
        start, end = record.pop("start"), record.pop("end")
        features.append(
            {
                "type": "Feature",
                "geometry": {"type": "LineString", "coordinates": [start, end]},
                "properties": record,
            }
        )
    # RFC 7946 coordinates are WGS84 unless agreed otherwise: "crs" (the 2008 GeoJSON
    # member, which GDAL still reads) names a local engineering frame in metres, and
    # "frame" says it in words with the local origin.
    collection = {
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": LOCAL_CRS}},
        "frame": frame_record(lines),
        "features": features,
        "scanlines": meta,
    }
    return dumps(collection)


#: The GeoJSON ``crs`` of a map: a local (engineering) frame in metres, as WKT.
LOCAL_CRS = 'LOCAL_CS["scanlines map: the log\'s world frame",UNIT["metre",1]]'


def _json(lines: MapLines, meta: dict[str, Any]) -> str:
    document = {
        "format": "scanlines line map",
        "frame": frame_record(lines),
        "covariance": "of (rho, alpha), in the local frame",
        **meta,
        "lines": map_records(lines),
    }
    return dumps(document)


def _svg(lines: MapLines, meta: dict[str, Any], margin: float = 1.0, scale: float = 20.0) -> str:
    """Metres about the map's local origin (``lines.origin``, written in the file): the
    ``viewBox`` is in metres, y up (the SVG's y axis flipped: an SVG ``y`` is ``-y``);
    displayed at ``scale`` pixels per metre."""
    if len(lines):
        points = np.vstack((lines.start, lines.end))
        lo, hi = points.min(axis=0) - margin, points.max(axis=0) + margin
    else:
        lo, hi = np.array([-margin, -margin]), np.array([margin, margin])
    width, height = hi - lo
    body = []
    for k in range(len(lines)):
        (x0, y0), (x1, y1) = lines.start[k], lines.end[k]
        body.append(
            f'<line x1="{x0:.4f}" y1="{-y0:.4f}" x2="{x1:.4f}" y2="{-y1:.4f}">'
            f"<title>line {k}: {int(lines.scans[k])} scans</title></line>"
        )
    title = meta.get("log", "line map")
    ox, oy = (float(v) for v in lines.origin)
    desc = (
        f"Units: metres (1 user unit = 1 m). x right, y up: an SVG y is minus the map's y. "
        f"Origin: the point ({ox!r}, {oy!r}) of the log's world frame; add it to every "
        "coordinate for the world's."
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width * scale:.0f}" '
        f'height="{height * scale:.0f}" '
        f'viewBox="{lo[0]:.4f} {-hi[1]:.4f} {width:.4f} {height:.4f}" '
        f'data-units="m" data-origin-x="{ox!r}" data-origin-y="{oy!r}">\n'
        f"<title>{_escape(str(title))}: {len(lines)} lines</title>\n"
        f"<desc>{_escape(desc)}</desc>\n"
        f'<rect x="{lo[0]:.4f}" y="{-hi[1]:.4f}" width="{width:.4f}" height="{height:.4f}" '
        'fill="white"/>\n'
        '<g stroke="black" stroke-width="0.05" stroke-linecap="round">\n'
        + "\n".join(body)
        + "\n</g>\n</svg>\n"
    )


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _write_dxf(lines: MapLines, path: Path, meta: dict[str, Any], overwrite: bool) -> Path:
    ezdxf = _ezdxf()
    target = check_output(path, overwrite=overwrite)
    document = ezdxf.new("R2010", units=6)  # 6: metres
    document.layers.add("MAP_LINES")
    space = document.modelspace()
    start, end = lines.world_start, lines.world_end
    for k in range(len(lines)):
        space.add_line(
            tuple(float(v) for v in start[k]),
            tuple(float(v) for v in end[k]),
            dxfattribs={"layer": "MAP_LINES"},
        )
    document.header["$PROJECTNAME"] = str(meta.get("log", ""))[:250]
    temporary = temp_path(target)
    try:
        document.saveas(temporary)
        os.chmod(temporary, 0o644)
        commit([(temporary, target)], overwrite=overwrite)
    except BaseException:
        discard(temporary)
        raise
    return target
