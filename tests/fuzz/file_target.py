"""The targets of the files that set things: parameters files and configurations
(``params``), sensor profiles (``profiles``) and the line maps ``localize`` reads
(``linemaps``), mutated (``mutate_files.py``) and read through ``file_channels.py``.

An input is a folder: the file (``params.yaml``, ``config.toml``, ``profile.json`` or
``map.json``) beside a CARMEN excerpt of the Intel sample (``log.clf``) the settings are
run on; a line map's folder also holds ``initial.txt``, the pose ``localize`` starts from.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from .mutate import BYTE_MUTATORS, LINE_MUTATORS
from .mutate_files import JSON_MUTATORS, LINE_MAP_MUTATORS, TOML_MUTATORS, YAML_MUTATORS
from .plans import Plan, interleave
from .seeds import carmen_excerpt, intel_scans

#: Seed name -> (target, the folder's file that is mutated).
FILE_SEEDS = {
    "params-yaml": ("params", "params.yaml"),
    "config-toml": ("params", "config.toml"),
    "profile-json": ("profiles", "profile.json"),
    "line-map": ("linemaps", "map.json"),
}
SETTINGS_SCANS = 8
MAP_SCANS = 20

PARAMS_YAML = """\
# the node's parameters (docs/ros2/params.yaml, shortened)
/**/scanlines:
  ros__parameters:
    method: adaptive
    min_points: 3
    min_length: 0.0
    max_residual: 0.1
    dkth_range: [0.0, 0.05]
    topic: scan
    segments_topic: line_segments
    markers_topic: ""
other_node:
  ros__parameters:
    rate: 10
"""
CONFIG_TOML = """\
# scanlines extraction configuration
method = "iepf"

[params]
min_points = 4
min_length = 0.1
max_residual = "none"
"""


def seeds_of(target: str) -> tuple[str, ...]:
    return tuple(name for name, (of, _) in FILE_SEEDS.items() if of == target)


def build_file_seeds(folder: Path, target: str) -> dict[str, Path]:
    """Write the seeds of ``target`` into ``folder``; ``{seed name: folder}``."""
    paths = {}
    for name in seeds_of(target):
        path = folder / name
        shutil.rmtree(path, ignore_errors=True)
        path.mkdir(parents=True)
        paths[name] = path
    if target == "params":
        log = carmen_excerpt("intel", SETTINGS_SCANS)
        (paths["params-yaml"] / "params.yaml").write_text(PARAMS_YAML)
        (paths["params-yaml"] / "log.clf").write_text(log)
        (paths["config-toml"] / "config.toml").write_text(CONFIG_TOML)
        (paths["config-toml"] / "log.clf").write_text(log)
    elif target == "profiles":
        _profile_seed(paths["profile-json"])
    else:
        _map_seed(paths["line-map"])
    return paths


def _profile_seed(folder: Path) -> None:
    from scanlines.sensor.profile import estimate_profile

    scans = intel_scans(MAP_SCANS)
    estimate_profile(scans, source="intel").save(folder / "profile.json")
    (folder / "log.clf").write_text(carmen_excerpt("intel", SETTINGS_SCANS))


def _map_seed(folder: Path) -> None:
    from scanlines.map import build_map
    from scanlines.map.export import write_map

    scans = intel_scans(MAP_SCANS)
    build = build_map(enumerate(scans))
    write_map(build.line_map.lines(), folder / "map.json", overwrite=True)
    (folder / "log.clf").write_text(carmen_excerpt("intel", MAP_SCANS))
    t, (x, y, yaw) = scans[0].timestamp, scans[0].pose
    (folder / "initial.txt").write_text(f"{t!r},{x!r},{y!r},{yaw!r}\n")


def file_plans(seed_name: str) -> list[Plan]:
    """Every plan tried on the seed ``seed_name``."""
    _, file = FILE_SEEDS[seed_name]
    text = LINE_MUTATORS | {k: BYTE_MUTATORS[k] for k in ("flip_bits", "truncate", "insert_nuls")}
    own = {
        "params-yaml": YAML_MUTATORS,
        "config-toml": TOML_MUTATORS,
        "profile-json": JSON_MUTATORS,
        "line-map": JSON_MUTATORS | LINE_MAP_MUTATORS,
    }[seed_name]
    # the file's own mutators twice as often as the generic ones
    mine = [Plan(name, m, file) for name, m in own.items()]
    return interleave(mine, [Plan(name, m, file) for name, m in text.items()], mine)


def file_input_kind(path: Path) -> str | None:
    """The target of an input folder, by the file it holds (None: not such an input)."""
    if path.is_dir():
        for target, file in FILE_SEEDS.values():
            if (path / file).is_file():
                return target
    return None
