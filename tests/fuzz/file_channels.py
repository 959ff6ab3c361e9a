"""The channels of the settings-file targets (``file_target.py``), in-process, classified.

``read settings``
    ``params.yaml``: the node's parameters read as ``scanlines ros2 --ros-args
    --params-file`` reads them (``parse_ros_args``, ``apply_parameters``, the sensor
    profile they name); ``config.toml``: ``load_config``.
``extract settings``
    ``params.yaml``: what the node would then run, an ``Extractor`` of those options over
    every scan of ``log.clf``; ``config.toml``: ``scanlines run log.clf --config``.
``read profile``, ``run profile``
    ``read_profile``; ``scanlines run log.clf --sensor-profile profile.json``.
``read map``, ``localize``
    ``read_line_map``; ``scanlines localize log.clf --map map.json --initial-pose ...``.

A library channel succeeds without an exception; its clean error is a
:class:`~scanlines.ScanlinesError` of one line of at most :data:`MAX_MESSAGE` characters
(a value is quoted in 80). A command's outcomes
are those of ``channels.py``; ``localize`` must also write strict JSON covariances.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from .map_channels import strict_json

FILE_CHANNELS = {
    "params": ("read settings", "extract settings"),
    "profiles": ("read profile", "run profile"),
    "linemaps": ("read map", "localize"),
}
ALL_FILE_CHANNELS = tuple(c for channels in FILE_CHANNELS.values() for c in channels)
#: The longest one-line error a hostile file may give (an unknown parameter lists the
#: valid ones: about 500 characters and the path).
MAX_MESSAGE = 1000
#: stderr lines ``localize`` and ``run`` may print besides their error line.
FILE_NOTICES = ("sensor profile:", "poses:")


def _settings_file(path: Path) -> Path:
    yaml = path / "params.yaml"
    return yaml if yaml.exists() else path / "config.toml"


def node_options(params: Path):
    """The node's options from the parameters file (as ``scanlines ros2`` makes them)."""
    from scanlines.ros2.parameters import NodeOptions, apply_parameters
    from scanlines.ros2.ros_args import parse_ros_args

    values = parse_ros_args(["--params-file", str(params)]).parameters([])
    options = NodeOptions("adaptive", topics={"topic": "scan", "segments_topic": "segments"})
    return apply_parameters(options, values)


def read_settings(path: Path) -> None:
    from scanlines.config import load_config
    from scanlines.sensor.profile import read_profile

    file = _settings_file(path)
    if file.suffix == ".toml":
        load_config(file)
        return
    options = node_options(file)
    if options.sensor_profile is not None:
        read_profile(options.sensor_profile)


def extract_settings(path: Path) -> None:
    from scanlines.extractor import Extractor
    from scanlines.io import open_log
    from scanlines.sensor.profile import read_profile

    options = node_options(path / "params.yaml")
    profile = None if options.sensor_profile is None else read_profile(options.sensor_profile)
    extractor = Extractor(options.method, options.preset, sensor_profile=profile, **options.params)
    with open_log(path / "log.clf") as reader:
        for scan in reader:
            extractor(scan)


def library_outcome(channel: str, call, path: Path):
    """``call(path)`` classified (module docstring)."""
    from scanlines.errors import ScanlinesError

    from .channels import CLEAN_ERROR, DEFECT, SUCCESS, Outcome, all_lines, first_line, type_name

    try:
        call(path)
    except ScanlinesError as exc:
        message = str(exc)
        if len(message.splitlines()) > 1:
            return Outcome(channel, DEFECT, "multi-line message", all_lines(message))
        if len(message) > MAX_MESSAGE:
            return Outcome(channel, DEFECT, "long message", f"{len(message)} characters")
        return Outcome(channel, CLEAN_ERROR, type(exc).__name__, first_line(message))
    except Exception as exc:
        return Outcome(channel, DEFECT, type_name(exc), first_line(str(exc)))
    return Outcome(channel, SUCCESS)


def command_args(channel: str, path: Path, out: Path) -> list[str]:
    log = str(path / "log.clf")
    if channel == "extract settings":
        return ["run", log, "--config", str(path / "config.toml"), "--out", str(out / "o.jsonl")]
    if channel == "run profile":
        profile = str(path / "profile.json")
        return ["run", log, "--sensor-profile", profile, "--out", str(out / "o.jsonl")]
    initial = (path / "initial.txt").read_text().strip()
    return ["localize", log, "--map", str(path / "map.json"), "--initial-pose", initial,
            "--out", str(out / "p.tum")]  # fmt: skip


def command_outcome(channel: str, path: Path, out: Path):
    from typer.testing import CliRunner

    from scanlines.cli import app

    from .channels import DEFECT, SUCCESS, Outcome, classify_failure

    result = CliRunner().invoke(app, command_args(channel, path, out))
    if result.exit_code != 0:
        outcome = classify_failure(channel, result, FILE_NOTICES)
        if len(outcome.message) > MAX_MESSAGE:
            return Outcome(channel, DEFECT, "long message", f"{len(outcome.message)} characters")
        return outcome
    if channel == "localize":
        try:
            strict_json(out / "p.cov.json")
        except (OSError, ValueError) as exc:
            return Outcome(channel, DEFECT, "bad covariances", str(exc))
    return Outcome(channel, SUCCESS)


def file_channel(channel: str, path: Path, workdir: Path):
    """One settings-file channel on the input folder ``path``."""
    if workdir.exists():
        shutil.rmtree(workdir)
    workdir.mkdir(parents=True)
    if channel == "read settings":
        return library_outcome(channel, read_settings, path)
    if channel == "extract settings" and (path / "params.yaml").exists():
        return library_outcome(channel, extract_settings, path)
    if channel == "read profile":
        from scanlines.sensor.profile import read_profile

        return library_outcome(channel, lambda p: read_profile(p / "profile.json"), path)
    if channel == "read map":
        from scanlines.map.localize import read_line_map

        return library_outcome(channel, lambda p: read_line_map(p / "map.json"), path)
    return command_outcome(channel, path, workdir)
