"""The node's ROS 2 parameters: scanlines' own names, checked, over the command's options.

A parameter set by ``--ros-args`` (``-p``, ``--params-file``) overrides the option of the
same name (``method`` over ``--method``, ``markers_topic`` over ``--markers-topic``...);
each method parameter (``min_points``...) overrides ``--param`` and ``--config``. Values
keep the type YAML gave them, checked as a ``--config`` file's are (a number is written
without quotes, a pair as ``[a, b]``). ROS has no null: an empty string unsets ``preset``
and ``sensor_profile`` and turns off the optional outputs.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from scanlines.errors import ParameterError
from scanlines.ros2.names import expand
from scanlines.ros2.ros_args import Parameter
from scanlines.untrusted import clip, quote

__all__ = ["NODE_PARAMETERS", "OPTIONAL_TOPICS", "TOPICS", "NodeOptions", "apply_parameters"]

#: The node's own parameters (the method's are the others), with what they set.
NODE_PARAMETERS = {
    "method": "the extraction method (--method)",
    "preset": "the method's preset (--preset)",
    "sensor_profile": "a sensor profile's path (--sensor-profile)",
    "topic": "the LaserScan topic (--topic)",
    "segments_topic": "laser_line_extraction's LineSegmentList topic (--segments-topic)",
    "markers_topic": "laser_line_extraction's Marker topic (--markers-topic)",
    "marker_array_topic": "the MarkerArray topic (--marker-array-topic)",
    "features_topic": "the ScanFeatures topic (--features-topic)",
    "use_sim_time": "taken, no effect: every output carries its scan's stamp",
    "map": "a line map to localise on (--map; empty: none)",
    "odometry": "where the odometry comes from, odom or tf (--odometry)",
    "global_frame_id": "the map's frame, AMCL's name (--global-frame)",
    "odom_frame_id": "the odometry's frame, AMCL's name (--odom-frame)",
    "base_frame_id": "the robot's frame, AMCL's name (--base-frame)",
}
#: The live localisation's parameters (strings).
LIVE = ("map", "odometry", "global_frame_id", "odom_frame_id", "base_frame_id")
#: The topic parameters, and those an empty name turns off.
TOPICS = ("topic", "segments_topic", "markers_topic", "marker_array_topic", "features_topic")
OPTIONAL_TOPICS = ("markers_topic", "marker_array_topic", "features_topic")


@dataclass
class NodeOptions:
    """What the node runs: method, preset, parameter overrides (as
    :class:`~scanlines.Extractor` takes them), sensor profile, and the topics by
    parameter name, as given (before namespace and remapping; ``None``: not published)."""

    method: str
    preset: str | None = None
    params: dict[str, Any] = field(default_factory=dict)
    sensor_profile: Path | None = None
    topics: dict[str, str | None] = field(default_factory=dict)
    live: dict[str, str | None] = field(default_factory=dict)


def apply_parameters(options: NodeOptions, values: dict[str, Parameter]) -> NodeOptions:
    """``options`` with the ROS parameters ``values`` applied, each checked.

    Raises
    ------
    ParameterError
        One line naming the parameter and where it was set, for an unknown parameter (the
        valid ones listed) or a value of the wrong type or outside its domain.
    """
    from scanlines.methods import method_class

    def fail(name: str, reason: str) -> ParameterError:
        origin = values[name].origin
        return ParameterError(f"--ros-args: parameter {clip(name)} ({origin}): {reason}")

    def text(name: str) -> str | None:
        """A string parameter's value (``None``: not set)."""
        if name not in values:
            return None
        value = values[name].value
        if not isinstance(value, str):
            raise fail(name, f"a string, got {quote(value)}")
        return value

    method = text("method")
    if method is not None:
        try:
            method_class(method)
        except ParameterError as error:
            raise fail("method", str(error)) from None
    else:
        method = options.method
    preset = text("preset")
    preset = options.preset if preset is None else preset or None
    spec = method_class(method).parameters
    method_params = {}
    for name, parameter in values.items():
        if name in NODE_PARAMETERS:
            continue
        if name not in spec:
            raise fail(name, _unknown(name, method, spec))
        method_params[name] = parameter.value
    if "use_sim_time" in values and not isinstance(values["use_sim_time"].value, bool):
        raise fail("use_sim_time", f"true or false, got {quote(values['use_sim_time'].value)}")
    checked = _checked(method, preset, method_params, values, fail)
    profile = text("sensor_profile")
    if profile is not None:
        options = replace(options, sensor_profile=Path(profile) if profile else None)
    topics = _topics(options.topics, text, fail)
    live = _live(options.live, text, fail)
    return replace(
        options,
        method=method,
        preset=preset,
        params={**options.params, **checked},
        sensor_profile=options.sensor_profile
        if profile is None
        else Path(profile)
        if profile
        else None,
        topics=topics,
        live=live,
    )


def _topics(topics: dict[str, str | None], text, fail) -> dict[str, str | None]:
    """The node's topics with those set by parameters (``text(name)``), each checked."""
    topics = dict(topics)
    for name in TOPICS:
        given = text(name)
        if given is None:
            continue
        if not given and name not in OPTIONAL_TOPICS:
            raise fail(name, "a topic name, got an empty string")
        try:
            if given:
                expand(given, "node", "/")
        except ParameterError as error:
            raise fail(name, str(error)) from None
        topics[name] = given or None
    return topics


def _live(live: dict[str, str | None], text, fail) -> dict[str, str | None]:
    """The live localisation's frames and odometry source with those set by parameters."""
    live = dict(live)
    for name in LIVE:
        given = text(name)
        if given is None:
            continue
        if name == "odometry" and given not in ("odom", "tf"):
            raise fail(name, f"odom or tf, got {quote(given)}")
        if not given and name != "map":
            raise fail(name, "a frame's name, got an empty string")
        live[name] = given or None
    return live


def _checked(method, preset, params, values, fail) -> dict[str, Any]:
    """``params`` checked as a ``--config`` file's, converted (``[a, b]`` a pair...)."""
    from scanlines.config import ConfigError, ExtractionConfig

    try:
        config = ExtractionConfig.from_dict(
            {"method": method, "preset": preset, "params": params}, source="--ros-args"
        )
    except ConfigError as error:
        key = (error.key or "").removeprefix("params.")
        if key in values:
            raise fail(key, error.reason) from None
        raise ParameterError(f"--ros-args: {error.reason}") from None
    return dict(config.params)


def _unknown(name: str, method: str, spec) -> str:
    valid = [*NODE_PARAMETERS, *spec]
    close = difflib.get_close_matches(name, valid, n=1)
    hint = f"did you mean {close[0]}? " if close else ""
    return (
        f"unknown; {hint}the node's parameters: {', '.join(NODE_PARAMETERS)}; "
        f"method {method}'s: {', '.join(spec)}"
    )
