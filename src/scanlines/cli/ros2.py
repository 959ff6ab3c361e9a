"""``scanlines ros2``: the line-extraction node on a ROS 2 LaserScan topic, or ``--play`` a log.

Beside its options the command takes ROS 2's own arguments after ``--ros-args`` (remapping,
namespace, node name, ``-p`` parameters and ``--params-file``: :mod:`scanlines.ros2.ros_args`),
as ``ros2 run`` and launch files pass them.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from typer.core import TyperCommand

from scanlines.cli.common import (
    NPZ_HELP,
    ConfigMethodOption,
    ConfigOption,
    OnErrorOption,
    ParamOption,
    PresetOption,
    RangeMaxOption,
    ScansOption,
    guarded,
    method_options,
)
from scanlines.cli.interrupts import is_interrupt

#: Where :class:`RosArgsCommand` leaves the words of the ``--ros-args`` sections.
ROS_ARGS = "scanlines.ros_args"

HELP = (
    "ROS 2 node over DDS (no ROS install): LaserScan in; laser_line_extraction's line "
    "segments and Marker, and a MarkerArray, out; with --map MAP.json it also localises "
    "each scan on the map as AMCL does (amcl_pose, map -> odom on /tf, /initialpose, the map "
    "on /map). --play LOG publishes a log's scans (its odometry on /odom and /tf, the "
    "mounting on /tf_static). ROS arguments follow --ros-args: -r FROM:=TO (-r __ns:=/NS, "
    "-r __node:=NAME), -p NAME:=VALUE, --params-file FILE (NAME: ros__parameters: ...); "
    "parameters are the options' names with _ (method, preset, sensor_profile, topic, "
    "markers_topic, map, odometry...), AMCL's global_frame_id, odom_frame_id and "
    "base_frame_id, and the method's parameters."
)


class RosArgsCommand(TyperCommand):
    """A command whose ``--ros-args`` sections (to ``--`` or the end) are taken off the
    command line before its options are parsed, into ``ctx.meta[ROS_ARGS]``."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        from scanlines.ros2.ros_args import split_ros_args

        own, ros = split_ros_args(args)
        ctx.meta[ROS_ARGS] = ros
        return super().parse_args(ctx, own)


def register(app: typer.Typer) -> None:
    app.command("ros2", cls=RosArgsCommand, help=HELP)(guarded(ros2_command))


def _domain_default() -> int:
    value = os.environ.get("ROS_DOMAIN_ID", "0")
    return int(value) if value.isdigit() else 0


NodeProfileOption = Annotated[
    Path | None,
    typer.Option(
        "--sensor-profile",
        help="Sensor profile from `scanlines calibrate` on a log of this sensor: the range "
        "noise every scan's thresholds and covariances take (default: each scan's noise "
        "measured from that scan alone; the start-up line says which).",
    ),
]


def ros2_command(
    ctx: typer.Context,
    method: ConfigMethodOption = None,
    preset: PresetOption = None,
    param: ParamOption = None,
    config: ConfigOption = None,
    sensor_profile: NodeProfileOption = None,
    play: Annotated[
        Path | None,
        typer.Option("--play", metavar="LOG", help=f"Publish this log's scans instead. {NPZ_HELP}"),
    ] = None,
    rate: Annotated[
        float | None,
        typer.Option(help="--play: scans per second (default: the recorded rate).", min=0.01),
    ] = None,
    scans: ScansOption = None,
    on_error: OnErrorOption = "fail",
    range_max: RangeMaxOption = None,
    topic: Annotated[
        str, typer.Option(help="The LaserScan topic (relative: under the namespace).")
    ] = "scan",
    segments_topic: Annotated[
        str, typer.Option(help="laser_line_extraction's LineSegmentList topic.")
    ] = "line_segments",
    markers_topic: Annotated[
        str,
        typer.Option(help="laser_line_extraction's Marker topic: the segments as a line list."),
    ] = "line_markers",
    marker_array_topic: Annotated[
        str, typer.Option(help="MarkerArray topic: segments, breakpoints and corners.")
    ] = "scanlines/markers",
    features_topic: Annotated[
        str | None,
        typer.Option(help="Also publish the full result (scanlines/msg/ScanFeatures) here."),
    ] = None,
    frame_id: Annotated[
        str, typer.Option(help="--play: the scans' frame_id (the laser's frame).")
    ] = "laser",
    odom_frame: Annotated[str, typer.Option(help="The odometry's frame.")] = "odom",
    base_frame: Annotated[str, typer.Option(help="The robot's frame (odometry's child).")] = (
        "base_link"
    ),
    restamp: Annotated[
        bool,
        typer.Option(
            help="--play: stamps that only go forward: the log's intervals where positive, "
            "the median positive interval where the log's clock steps back."
        ),
    ] = False,
    map_file: Annotated[
        Path | None,
        typer.Option(
            "--map",
            metavar="MAP.json",
            help="Node: localise each scan on this line map (`scanlines map` writes it) "
            "from the pose given on /initialpose (or --initial-pose).",
        ),
    ] = None,
    odometry: Annotated[
        str,
        typer.Option(
            help="--map: the odometry from the odom topic (nav_msgs/Odometry) or from /tf "
            "(odom-frame -> base-frame).",
        ),
    ] = "odom",
    global_frame: Annotated[str, typer.Option(help="--map: the map's frame.")] = "map",
    initial_pose: Annotated[
        str | None,
        typer.Option(
            help="--map: X,Y,YAW: where the robot's base stands in the map (metres, radians) "
            "at the first scan, as if sent on /initialpose (which may still move it).",
        ),
    ] = None,
    domain_id: Annotated[
        int, typer.Option(help="ROS domain id.", show_default="$ROS_DOMAIN_ID, else 0")
    ] = _domain_default(),
    loopback: Annotated[
        bool,
        typer.Option(
            "--loopback/--network",
            help="DDS sent over 127.0.0.1 only (Cyclone still listens on every interface: "
            "see the README), or as configured.",
        ),
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
    from scanlines.config import DEFAULT_METHOD
    from scanlines.errors import ParameterError
    from scanlines.ros2.parameters import NodeOptions, apply_parameters

    try:
        import cyclonedds  # noqa: F401
    except ImportError:
        raise ParameterError(
            'scanlines ros2 needs Cyclone DDS: pip install "scanlines[ros2]"'
        ) from None
    ros, values = _ros_arguments(ctx.meta.get(ROS_ARGS))
    if play is not None:
        from scanlines.cli.ros2_play import play_log

        options = NodeOptions(DEFAULT_METHOD, topics={"topic": topic})
        options = apply_parameters(options, values)
        play_log(
            play, rate, scans, on_error, ros.resolve(options.topics["topic"]), ros.resolve("/tf"),
            frame_id, odom_frame, domain_id, loopback, wait, restamp=restamp,
            odom_topic=ros.resolve("odom"), tf_static_topic=ros.resolve("/tf_static"),
            base_frame=base_frame, range_max=range_max,
        )  # fmt: skip
        return
    chosen = NodeOptions(
        *method_options(method, preset, param, config),
        sensor_profile=sensor_profile,
        topics={
            "topic": topic,
            "segments_topic": segments_topic,
            "markers_topic": markers_topic or None,
            "marker_array_topic": marker_array_topic or None,
            "features_topic": features_topic or None,
        },
        live={
            "map": None if map_file is None else str(map_file),
            "odometry": odometry,
            "global_frame_id": global_frame,
            "odom_frame_id": odom_frame,
            "base_frame_id": base_frame,
        },
    )
    options = apply_parameters(chosen, values)
    live = _live_options(options.live)
    if live is not None:
        live = (*live, None if initial_pose is None else _pose(initial_pose))
    _node(options, ros, domain_id, loopback, max_scans, duration, live)


def _pose(text: str) -> tuple[float, float, float]:
    """``X,Y,YAW`` as numbers, or one line saying what is wrong."""
    import math

    from scanlines.errors import ParameterError

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ParameterError(
            f"--initial-pose: {text!r} is not X,Y,YAW (three finite numbers: metres, metres, "
            "radians)"
        )
    return values[0], values[1], values[2]


def _live_options(values: dict):
    """The map's path and the frames of the live localisation (``None``: no map)."""
    from scanlines.errors import ParameterError
    from scanlines.ros2.live import LiveFrames

    if values["odometry"] not in ("odom", "tf"):
        raise ParameterError(f"--odometry must be odom or tf, got {values['odometry']!r}")
    if values["map"] is None:
        return None
    frames = LiveFrames(values["global_frame_id"], values["odom_frame_id"],
                        values["base_frame_id"], values["odometry"])  # fmt: skip
    return Path(values["map"]), frames


def _ros_arguments(words: list[str] | None):
    """The ROS arguments of the command line and the parameters they set for this node
    (a line on stderr for each parameters file without an entry for it)."""
    from scanlines.errors import ParameterError
    from scanlines.ros2.ros_args import parse_ros_args

    ros = parse_ros_args(words or [])
    if ros.sources:
        try:
            import yaml  # noqa: F401
        except ImportError:
            raise ParameterError(
                '--ros-args parameters are YAML: pip install ".[ros2]" (PyYAML)'
            ) from None
    notes: list[str] = []
    values = ros.parameters(notes)
    for note in notes:
        print(f"scanlines ros2: {note}", file=sys.stderr, flush=True)
    return ros, values


def _read_map(map_file: Path):
    """The lines and frame of ``map_file``; one line when it is not there."""
    from scanlines.errors import NO_SUCH_FILE, ParameterError
    from scanlines.map.localize import read_line_map

    if not map_file.is_file():
        raise ParameterError(f"{map_file}: {NO_SUCH_FILE}")
    return read_line_map(map_file)


def _live(node, map_file, lines, frame, frames, initial, ros):
    """The node's localisation on the map (AMCL's topics, resolved), the map published;
    and its start-up line."""
    from scanlines.ros2.live import LiveLocalisation, LiveTopics
    from scanlines.ros2.localizer import Localizer

    topics = LiveTopics(*(ros.resolve(name) for name in (
        "odom", "/tf", "/tf_static", "initialpose", "amcl_pose", "map", "scanlines/map_markers"
    )))  # fmt: skip
    localizer = Localizer(lines, frame, base_frame=frames.base_frame)
    if initial is not None:
        localizer.set_initial(0.0, initial)
    live = LiveLocalisation(localizer, node.participant, topics=topics, frames=frames)
    node.attach(live)
    live.publish_map()
    source = (
        f"{topics.tf} ({frames.odom_frame} -> {frames.base_frame})"
        if frames.odometry == "tf"
        else f"{topics.odom} (Odometry)"
    )
    line = (
        f"scanlines ros2: localising on {map_file} ({len(lines.rho)} lines): odometry from "
        f"{source}, the laser's mounting from {topics.tf_static} (else the lever learnt), "
        f"the initial pose from {'--initial-pose, then ' if initial else ''}"
        f"{topics.initialpose}; publishing {topics.amcl_pose} "
        f"(PoseWithCovarianceStamped), {frames.global_frame} -> {frames.odom_frame} on "
        f"{topics.tf}, the map on {topics.map} (OccupancyGrid) and {topics.map_markers} "
        "(MarkerArray)"
    )
    return live, line


def _node(options, ros, domain_id, loopback, max_scans, duration, live=None) -> None:
    from scanlines.extractor import Extractor
    from scanlines.ros2 import LineNode
    from scanlines.sensor.profile import read_profile

    path = options.sensor_profile
    profile = None if path is None else read_profile(path)
    the_map = None if live is None else _read_map(live[0])  # before any DDS
    extractor = Extractor(options.method, options.preset, sensor_profile=profile, **options.params)
    topics = {
        name: None if given is None else ros.resolve(given)
        for name, given in options.topics.items()
    }
    node = LineNode(
        extractor,
        domain_id=domain_id,
        loopback=loopback,
        scan_topic=topics["topic"],
        segments_topic=topics["segments_topic"],
        markers_topic=topics["markers_topic"],
        marker_array_topic=topics["marker_array_topic"],
        features_topic=topics["features_topic"],
    )
    line = start_line(ros.fully_qualified_name, domain_id, extractor, options, path, topics)
    print(line, file=sys.stderr, flush=True)
    if live is not None:
        _, line = _live(node, live[0], *the_map, *live[1:], ros)
        print(line, file=sys.stderr, flush=True)
    try:
        node.spin(max_scans=max_scans, duration=duration)
    except BaseException as stop:
        if is_interrupt(stop):
            stop.add_note(_summary(node))  # the interrupt's one line carries it
        raise
    print(f"scanlines ros2: {_summary(node)}", file=sys.stderr, flush=True)


def _summary(node) -> str:
    text = node.stats.summary()
    if node.localisation is not None:
        text += f"; {node.localisation.stats.summary()}"
    return text


_KINDS = (
    ("segments_topic", "LineSegmentList"),
    ("markers_topic", "Marker"),
    ("marker_array_topic", "MarkerArray"),
    ("features_topic", "ScanFeatures"),
)


def start_line(node_name, domain_id, extractor, options, profile_path, topics) -> str:
    """The node's one start-up line: its name, the scan topic, the method (preset and
    parameters set), where the noise comes from, and the topics it publishes."""
    method = f"method {extractor.method}"
    if extractor.preset:
        method += f", preset {extractor.preset}"
    for name in options.params:
        method += f", {name}={extractor.params[name]!r}"
    profile = extractor.sensor_profile
    if profile is None:
        noise = "noise measured on each scan alone (no sensor profile)"
    else:
        noise = (
            f"noise from sensor profile {profile_path} (sigma(r) = "
            f"{profile.noise_sigma0 * 1e3:.3g} mm + {profile.noise_per_metre * 1e3:.3g} mm/m)"
        )
    published = ", ".join(f"{topics[name]} ({kind})" for name, kind in _KINDS if topics[name])
    return (
        f"scanlines ros2: node {node_name} (domain {domain_id}) listening on "
        f"{topics['topic']} (LaserScan); {method}; {noise}; publishing {published}"
    )
