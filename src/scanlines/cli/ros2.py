"""``scanlines ros2``: the line-extraction node on a ROS 2 LaserScan topic, or ``--play`` a log."""

from __future__ import annotations

import os
import sys
from collections import Counter
from pathlib import Path
from typing import Annotated

import typer

from scanlines.cli.common import (
    ConfigMethodOption,
    ConfigOption,
    OnErrorOption,
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
        typer.Option("--play", metavar="LOG", help="Publish this log's scans instead."),
    ] = None,
    rate: Annotated[
        float | None,
        typer.Option(help="--play: scans per second (default: the recorded rate).", min=0.01),
    ] = None,
    scans: ScansOption = None,
    on_error: OnErrorOption = "fail",
    topic: Annotated[str, typer.Option(help="The LaserScan topic.")] = "/scan",
    segments_topic: Annotated[
        str, typer.Option(help="laser_line_extraction's LineSegmentList topic.")
    ] = "/line_segments",
    markers_topic: Annotated[
        str, typer.Option(help="laser_line_extraction's Marker topic (the segments, a line list).")
    ] = "/line_markers",
    marker_array_topic: Annotated[
        str, typer.Option(help="MarkerArray topic: segments, breakpoints and corners.")
    ] = "/scanlines/markers",
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
        _play(play, rate, scans, on_error, topic, frame_id, domain_id, loopback, wait)
        return
    _node(
        method_options(method, preset, param, config),
        sensor_profile,
        topic,
        segments_topic,
        markers_topic,
        marker_array_topic,
        features_topic,
        domain_id,
        loopback,
        max_scans,
        duration,
    )


def _play(log, rate, scans, on_error, topic, frame_id, domain_id, loopback, wait) -> None:
    from scanlines.cli.common import reader_options
    from scanlines.cli.log_reports import _with_breakdown
    from scanlines.errors import ParameterError
    from scanlines.io import open_log
    from scanlines.ros2 import Player
    from scanlines.runner import parse_slice, select

    if on_error not in ("fail", "skip"):
        raise ParameterError(f"--on-error must be fail or skip, got {on_error!r}")
    selection = parse_slice(scans)
    player = Player(domain_id=domain_id, loopback=loopback, topic=topic, frame_id=frame_id)
    if not player.wait_for_subscriber(wait):
        typer.echo(f"scanlines ros2: no subscriber on {topic} after {wait:g} s; playing", err=True)
    skipped: Counter[str] = Counter()
    with open_log(log, options=reader_options(on_error=on_error)) as reader:
        pairs = select(reader.enumerate(), selection)
        count = player.play(_playable(pairs, log, on_error, skipped), rate=rate)
        skipped.update(reader.skip_reasons)
    text = f"scanlines ros2: published {count} scans of {log.name} on {topic}"
    if on_error == "skip":
        text += f"; scan records skipped: {_with_breakdown(sum(skipped.values()), skipped)}"
    typer.echo(text, err=True)


def _playable(pairs, log: Path, on_error: str, skipped: Counter[str]):
    """The scans of ``pairs`` (index, scan) that a LaserScan can carry. A timestamp that is
    no ROS 2 time (before 1970, or past 2**31 - 1 s) stops the play with an error naming the
    log, the scan and the field, or with ``--on-error skip`` is counted in ``skipped``."""
    from scanlines.errors import LogFormatError
    from scanlines.ros2.convert import stamp_problem

    for index, scan in pairs:
        problem = stamp_problem(scan.timestamp or 0.0)
        if problem is None:
            yield scan
        elif on_error == "skip":
            skipped["timestamp"] += 1
        else:
            reason = f"{problem}; --on-error skip skips such scans"
            raise LogFormatError(
                reason, path=log, record=index, field="timestamp", unit="scan index"
            )


def _node(
    chosen,
    sensor_profile,
    topic,
    segments_topic,
    markers_topic,
    marker_array_topic,
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
    node = LineNode(
        extractor,
        domain_id=domain_id,
        loopback=loopback,
        scan_topic=topic,
        segments_topic=segments_topic,
        markers_topic=markers_topic,
        marker_array_topic=marker_array_topic,
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
