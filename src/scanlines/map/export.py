"""A line map written as GeoJSON, SVG, DXF (ezdxf) or JSON with covariances."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from scanlines.errors import ParameterError
from scanlines.map.fusion import MapLines
from scanlines.outputs import check_output, commit, discard, temp_path, write_text_atomically

__all__ = ["MAP_FORMATS", "check_map_format", "map_records", "write_map"]

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


def map_records(lines: MapLines) -> list[dict[str, Any]]:
    """One dict per map line: geometry, estimate, covariance and support."""
    records = []
    for k in range(len(lines)):
        records.append(
            {
                "start": [float(v) for v in lines.start[k]],
                "end": [float(v) for v in lines.end[k]],
                "rho": float(lines.rho[k]),
                "alpha": float(lines.alpha[k]),
                "covariance": [[float(v) for v in row] for row in lines.covariances[k]],
                "length": float(np.hypot(*(lines.end[k] - lines.start[k]))),
                "scans": int(lines.scans[k]),
                "returns": int(lines.returns[k]),
                "segments": int(lines.segments[k]),
                "first_scan": int(lines.first_scan[k]),
                "last_scan": int(lines.last_scan[k]),
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
        return _write_dxf(lines, path, meta, overwrite)
    text = {".geojson": _geojson, ".json": _json, ".svg": _svg}[suffix](lines, meta)
    return write_text_atomically(path, text, overwrite=overwrite)


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
    # Coordinates are metres in the log's world frame, not WGS84 (RFC 7946 allows other
    # reference systems by prior arrangement; "scanlines" says which one).
    collection = {"type": "FeatureCollection", "features": features, "scanlines": meta}
    return json.dumps(collection, indent=1) + "\n"


def _json(lines: MapLines, meta: dict[str, Any]) -> str:
    document = {
        "format": "scanlines line map",
        "frame": "the log's world frame (metres, radians); lines x cos(alpha) + y sin(alpha) = rho",
        "covariance": "of (rho, alpha)",
        **meta,
        "lines": map_records(lines),
    }
    return json.dumps(document, indent=1) + "\n"


def _svg(lines: MapLines, meta: dict[str, Any], margin: float = 1.0, scale: float = 20.0) -> str:
    """World metres at ``scale`` pixels per metre, y up (the SVG's y axis flipped)."""
    if len(lines):
        points = np.vstack((lines.start, lines.end))
        lo, hi = points.min(axis=0) - margin, points.max(axis=0) + margin
    else:
        lo, hi = np.array([-margin, -margin]), np.array([margin, margin])
    width, height = (hi - lo) * scale
    body = []
    for k in range(len(lines)):
        (x0, y0), (x1, y1) = lines.start[k], lines.end[k]
        body.append(
            f'<line x1="{(x0 - lo[0]) * scale:.2f}" y1="{(hi[1] - y0) * scale:.2f}" '
            f'x2="{(x1 - lo[0]) * scale:.2f}" y2="{(hi[1] - y1) * scale:.2f}">'
            f"<title>line {k}: {int(lines.scans[k])} scans</title></line>"
        )
    title = meta.get("log", "line map")
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0f}" height="{height:.0f}" '
        f'viewBox="0 0 {width:.2f} {height:.2f}">\n'
        f"<title>{_escape(str(title))}: {len(lines)} lines</title>\n"
        f'<rect width="100%" height="100%" fill="white"/>\n'
        f'<g stroke="black" stroke-width="{max(0.05 * scale, 1.0):.2f}" '
        'stroke-linecap="round">\n' + "\n".join(body) + "\n</g>\n</svg>\n"
    )


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _write_dxf(lines: MapLines, path: Path, meta: dict[str, Any], overwrite: bool) -> Path:
    ezdxf = _ezdxf()
    target = check_output(path, overwrite=overwrite)
    document = ezdxf.new("R2010", units=6)  # 6: metres
    document.layers.add("MAP_LINES")
    space = document.modelspace()
    for k in range(len(lines)):
        space.add_line(
            tuple(float(v) for v in lines.start[k]),
            tuple(float(v) for v in lines.end[k]),
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
