"""The map channels: a map input (``log.clf``, and ``poses.tum`` where there is one) run
through ``scanlines map`` and ``scanlines eval map``, in-process, and classified.

``map``
    ``scanlines map LOG --out DIR/map.geojson [--poses TUM]``.
``eval map``
    ``scanlines eval map LOG --out DIR/eval [--poses TUM]``.

Success is exit code 0 with an output that a strict JSON parser reads (no ``NaN`` or
``Infinity``) and whose coordinates are finite numbers. A clean error and the defects are
those of the other commands (``channels.py``), and also: an input file changed by the
command (a user's file is never modified).
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
from pathlib import Path

MAP_CHANNELS = ("map", "eval map")
#: stderr lines the map commands may print besides their error line.
MAP_NOTICES = ("poses:",)


def fingerprint(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def strict_json(path: Path):
    def refuse(constant: str):
        raise ValueError(f"a bare {constant}")

    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


def check_output(channel: str, out: Path):
    """The outcome of a command that exited 0 (``channels.Outcome``)."""
    from .channels import DEFECT, SUCCESS, Outcome

    target = out if channel == "map" else out / "map_eval.json"
    if not target.exists():
        return Outcome(channel, DEFECT, "no output", f"exit 0 but {target.name} missing")
    try:
        document = strict_json(target)
    except ValueError as exc:
        return Outcome(channel, DEFECT, "invalid JSON", f"{target.name}: {exc}")
    if channel == "map":
        if "origin" not in document.get("frame", {}):
            return Outcome(channel, DEFECT, "no frame", "the GeoJSON does not state its frame")
        numbers = [v for f in document["features"] for e in f["geometry"]["coordinates"] for v in e]
        numbers += document["frame"]["origin"]
        if not all(isinstance(v, float | int) and math.isfinite(v) for v in numbers):
            return Outcome(channel, DEFECT, "bad coordinates", "a coordinate is not a number")
    return Outcome(channel, SUCCESS, scans=document.get("scans", document.get("mapped_scans")))


def map_channel(channel: str, path: Path, workdir: Path):
    from typer.testing import CliRunner

    from scanlines.cli import app

    from .channels import DEFECT, Outcome, classify_failure

    if workdir.exists():
        shutil.rmtree(workdir)
    workdir.mkdir(parents=True)
    log, poses = path / "log.clf", path / "poses.tum"
    before = fingerprint(path)
    if channel == "map":
        out = workdir / "map.geojson"
        args = ["map", str(log), "--out", str(out)]
    else:
        out = workdir / "eval"
        args = ["eval", "map", str(log), "--out", str(out)]
    if poses.exists():
        args += ["--poses", str(poses)]
    result = CliRunner().invoke(app, args)
    if fingerprint(path) != before:
        return Outcome(channel, DEFECT, "input modified", f"{channel} changed a file of {path}")
    if result.exit_code == 0:
        return check_output(channel, out)
    return classify_failure(channel, result, MAP_NOTICES)
