"""``scanlines ros2``: the line-extraction node on a ROS 2 LaserScan topic, or ``--play`` a log."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Annotated

import typer

from scanlines.cli.common import (
    NPZ_HELP,
    ConfigMethodOption,
    ConfigOption,
    ParamOption,
    PresetOption,
    ProfileOption,
    ScansOption,
    guarded,
    method_options,
)
from scanlines.interrupts import is_interrupt


def register(app: typer.Typer) -> None:
    app.command(
        "ros2",
        help="ROS 2 node over DDS (no ROS install): LaserScan in, markers and "
        "laser_line_extraction line segments out; --play LOG publishes a log's scans.",
    )(guarded(ros2_command))


def _domain_default() -> int:
    value = os.environ.get("ROS_DOMAIN_ID", "0")
    return int(value) if value.isdigit() else 0


def ros2_command(
    method: ConfigMethodOption = None,
    preset: PresetOption = None,
    param: ParamOption = None,
    config: ConfigOption = None,
    sensor_profile: ProfileOption = None,
    play: Annotated[
        Path | None,
        typer.Option("--play", metavar="LOG", help=f"Publish this log's scans instead. {NPZ_HELP}"),
    ] = None,
    rate: Annotated[
        float | None,
        typer.Option(help="--play: scans per second (default: the recorded rate).", min=0.01),
    ] = None,
    scans: ScansOption = None,
    topic: Annotated[str, typer.Option(help="The LaserScan topic.")] = "/scan",
    markers_topic: Annotated[str, typer.Option(help="MarkerArray topic.")] = "/line_markers",
    segments_topic: Annotated[
        str, typer.Option(help="laser_line_extraction LineSegmentList topic.")
    ] = "/line_segments",
    features_topic: Annotated[
        str | None,
        typer.Option(help="Also publish the full result (scanlines/msg/ScanFeatures) here."),
    ] = None,
    frame_id: Annotated[str, typer.Option(help="--play: the scans' frame_id.")] = "laser",
    domain_id: Annotated[
        int, typer.Option(help="ROS domain id.", show_default="$ROS_DOMAIN_ID, else 0")
    ] = _domain_default(),
    loopback: Annotated[
        bool,
        typer.Option("--loopback/--network", help="DDS on 127.0.0.1 only, or as configured."),
    ] = False,
    wait: Annotated[
        float, typer.Option(help="--play: seconds to wait for a subscriber first.", min=0)
    ] = 10.0,
    max_scans: Annotated[
        int | None, typer.Option(help="Node: stop after this many scans.", min=1)
    ] = None,
    duration: Annotated[
        float | None, typer.Option(help="Node: stop after this many seconds.", min=0)
    ] = None,
) -> None:
    from scanlines.errors import ParameterError

    try:
        import cyclonedds  # noqa: F401
    except ImportError:
        raise ParameterError(
            'scanlines ros2 needs Cyclone DDS: pip install "scanlines[ros2]"'
        ) from None
    if play is not None:
        _play(play, rate, scans, topic, frame_id, domain_id, loopback, wait)
        return
    _node(
        method_options(method, preset, param, config),
        sensor_profile,
        topic,
        markers_topic,
        segments_topic,
        features_topic,
        domain_id,
        loopback,
        max_scans,
        duration,
    )


def _play(log, rate, scans, topic, frame_id, domain_id, loopback, wait) -> None:
    from scanlines.io import open_log
    from scanlines.ros2 import Player
    from scanlines.runner import parse_slice, select

    selection = parse_slice(scans)
    with open_log(log) as reader:  # a missing or unreadable log before waiting for anyone
        player = Player(domain_id=domain_id, loopback=loopback, topic=topic, frame_id=frame_id)
        if not player.wait_for_subscriber(wait):
            note = f"scanlines ros2: no subscriber on {topic} after {wait:g} s; playing"
            typer.echo(note, err=True)
        scans_chosen = (scan for _, scan in select(reader.enumerate(), selection))
        count = player.play(scans_chosen, rate=rate)
    typer.echo(f"scanlines ros2: published {count} scans of {log.name} on {topic}", err=True)


def _node(
    chosen,
    sensor_profile,
    topic,
    markers_topic,
    segments_topic,
    features_topic,
    domain_id,
    loopback,
    max_scans,
    duration,
) -> None:
    from scanlines.extractor import Extractor
    from scanlines.ros2 import LineNode
    from scanlines.sensor_profile import read_profile

    method, preset, params = chosen
    profile = None if sensor_profile is None else read_profile(sensor_profile)
    extractor = Extractor(method, preset, sensor_profile=profile, **params)
    extractor.warm_up()  # compiled before the node subscribes: the first scan is not late
    node = LineNode(
        extractor,
        domain_id=domain_id,
        loopback=loopback,
        scan_topic=topic,
        markers_topic=markers_topic,
        segments_topic=segments_topic,
        features_topic=features_topic,
    )
    print(
        f"scanlines ros2: {extractor!r} listening on {topic} (domain {domain_id})",
        file=sys.stderr,
        flush=True,
    )
    try:
        node.spin(max_scans=max_scans, duration=duration)
    except BaseException as stop:
        if is_interrupt(stop):
            stop.add_note(node.stats.summary())  # the interrupt's one line carries it
        raise
    print(f"scanlines ros2: {node.stats.summary()}", file=sys.stderr, flush=True)
