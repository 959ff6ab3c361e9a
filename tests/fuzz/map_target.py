"""The map target of the fuzzer: map inputs (a CARMEN log with poses, and a TUM file of
them), mutated (``mutate_maps.py``) and run through ``scanlines map`` and ``scanlines eval
--map`` (``map_channels.py``).

A map input is a folder: ``log.clf`` and, for ``map-log-tum``, ``poses.tum``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from scanlines.map.poses import write_tum

from .mutate import LINE_MUTATORS
from .mutate_maps import POSE_MUTATORS, TUM_MUTATORS
from .plans import Plan, interleave
from .seeds import carmen_excerpt, intel_scans

#: Map seed name -> folder name.
MAP_SEED_FILES = {
    "map-log": "map_intel",
    "map-log-tum": "map_intel_tum",
    "map-log-odom": "map_freiburg",
}
MAP_SCANS = 20


def build_map_seeds(folder: Path) -> dict[str, Path]:
    """Write every map seed into ``folder`` and return ``{seed name: folder}``."""
    paths = {name: folder / file for name, file in MAP_SEED_FILES.items()}
    for path in paths.values():
        shutil.rmtree(path, ignore_errors=True)
        path.mkdir(parents=True)
    intel = carmen_excerpt("intel", MAP_SCANS)
    (paths["map-log"] / "log.clf").write_text(intel)
    (paths["map-log-tum"] / "log.clf").write_text(intel)
    scans = intel_scans(MAP_SCANS)
    write_tum(paths["map-log-tum"] / "poses.tum", [(s.timestamp, s.pose) for s in scans])
    params = ("robot_front_laser_max", "laser_front_laser_fov", "robot_frontlaser_offset")
    (paths["map-log-odom"] / "log.clf").write_text(carmen_excerpt("freiburg", 15, params))
    return paths


def map_plans(seed_name: str) -> list[Plan]:
    """Every plan tried on the map seed ``seed_name``."""
    log_plans = [Plan(f"log/{name}", m, "log.clf") for name, m in POSE_MUTATORS.items()]
    log_plans.append(Plan("log/bad_number", LINE_MUTATORS["bad_number"], "log.clf"))
    if seed_name != "map-log-tum":
        return log_plans
    tum_plans = [Plan(f"tum/{name}", m, "poses.tum") for name, m in TUM_MUTATORS.items()]
    return interleave(tum_plans, log_plans)
