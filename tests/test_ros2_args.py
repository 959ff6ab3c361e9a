"""The ROS arguments of ``scanlines ros2`` (``--ros-args``): names, remapping, parameters,
parameters files and the shipped launch file, read as rcl reads them (no DDS here)."""

from __future__ import annotations

import sys
import types
from pathlib import Path

import pytest

pytest.importorskip("yaml")

from cli_helpers import scanlines
from scanlines.data import sample
from scanlines.errors import ParameterError
from scanlines.ros2.names import Remap, expand, resolve
from scanlines.ros2.parameters import NodeOptions, apply_parameters
from scanlines.ros2.ros_args import parse_ros_args, split_ros_args

DOCS = Path(__file__).parents[1] / "docs" / "ros2"
TOPICS = {
    "topic": "scan",
    "segments_topic": "line_segments",
    "markers_topic": "line_markers",
    "marker_array_topic": "scanlines/markers",
    "features_topic": None,
}


def options() -> NodeOptions:
    return NodeOptions("adaptive", topics=dict(TOPICS))


def node_options(words: list[str], given: NodeOptions | None = None) -> NodeOptions:
    """What the node runs with ``--ros-args WORDS``."""
    return apply_parameters(given or options(), parse_ros_args(words).parameters())


# -- the command line's sections ------------------------------------------------------------


def test_ros_args_run_to_a_double_dash_or_the_end():
    words = ["--loopback", "--ros-args", "-r", "a:=b", "--", "--max-scans", "3"]
    assert split_ros_args(words) == (["--loopback", "--max-scans", "3"], ["-r", "a:=b"])
    words = ["--ros-args", "-p", "k:=1", "--", "--duration", "1", "--ros-args", "-r", "x:=y"]
    assert split_ros_args(words) == (["--duration", "1"], ["-p", "k:=1", "-r", "x:=y"])
    assert split_ros_args(["--loopback", "--", "x"]) == (["--loopback", "--", "x"], None)
    assert split_ros_args(["--ros-args"]) == ([], [])


# -- names ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "namespace", "expanded"),
    [
        ("scan", "/", "/scan"),
        ("scan", "/robot1", "/robot1/scan"),
        ("scanlines/markers", "/robot1", "/robot1/scanlines/markers"),
        ("/tf", "/robot1", "/tf"),
        ("~/lines", "/robot1", "/robot1/scanlines/lines"),
        ("~", "/", "/scanlines"),
        ("{node}/lines", "/a/b", "/a/b/scanlines/lines"),
    ],
)
def test_names_expand_under_the_namespace(name, namespace, expanded):
    assert expand(name, "scanlines", namespace) == expanded


@pytest.mark.parametrize("name", ["", "/", "a//b", "a/", "2scan", "sc-an", "~x", "{nodes}/a"])
def test_a_name_ros_refuses_is_named_in_the_error(name):
    with pytest.raises(ParameterError, match=r"not a ROS 2 topic name: "):
        expand(name, "scanlines", "/")


def test_remapping_matches_expanded_names_and_the_first_rule_wins():
    rules = [Remap("scan", "/front/scan"), Remap("/scan", "/other"), Remap("line_markers", "m")]
    assert resolve("scan", rules, "n", "/robot1") == "/front/scan"
    assert resolve("/scan", rules, "n", "/robot1") == "/other"  # scan is /robot1/scan here
    assert resolve("/scan", rules, "n", "/") == "/front/scan"  # and /scan there: first rule
    assert resolve("/front/scan", rules, "n", "/") == "/front/scan"
    assert resolve("line_markers", rules, "n", "/robot1") == "/robot1/m"
    assert resolve("/tf", rules, "n", "/robot1") == "/tf"
    only_other = [Remap("scan", "/x", node="other")]
    assert resolve("scan", only_other, "n", "/") == "/scan"
    assert resolve("scan", only_other, "other", "/") == "/x"


def test_node_name_and_namespace_rules():
    args = parse_ros_args(["-r", "__ns:=/robot1", "--remap", "__node:=lines", "-r", "scan:=s"])
    assert (args.node, args.namespace, args.fully_qualified_name) == (
        "lines",
        "/robot1",
        "/robot1/lines",
    )
    assert args.resolve("scan") == "/robot1/s"
    assert args.resolve("~/x") == "/robot1/lines/x"
    first = parse_ros_args(["-r", "__node:=a", "-r", "__node:=b", "-r", "__name:=c"])
    assert first.node == "a"  # as rcl: the first rule wins
    assert parse_ros_args([]).fully_qualified_name == "/scanlines"


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (["-r", "__ns:=robot1"], "-r __ns:=robot1: a namespace is absolute"),
        (["-r", "__node:=my-node"], "-r __node:=my-node: a node name is letters"),
        (["-r", "scan"], "-r takes [node:]NAME:=VALUE, got 'scan'"),
        (["-r", "scan:=a b"], "-r scan:=a b: not a ROS 2 topic name"),
        (["-p"], "-p needs a value"),
        (["--params"], "unknown argument '--params'"),
        (["-e", "enclave"], "unknown argument '-e'"),
    ],
)
def test_ros_arguments_ros_refuses_are_one_line_errors(words, message):
    with pytest.raises(ParameterError) as raised:
        parse_ros_args(words)
    assert message in str(raised.value)
    assert "\n" not in str(raised.value)


def test_log_flags_launch_adds_are_taken_without_effect():
    args = parse_ros_args(["--log-level", "debug", "--disable-stdout-logs", "-r", "a:=b"])
    assert args.remaps == [Remap("a", "b")]


# -- parameters ------------------------------------------------------------------------------


def test_p_values_are_yaml_typed_and_checked_as_a_config_files():
    got = node_options(
        ["-p", "min_points:=6", "-p", "dkth_range:=[0.0, 0.05]", "-p", "merge:=false",
         "-p", "max_residual:=none", "-p", "preset:=paper", "-p", "use_sim_time:=true"]
    )  # fmt: skip
    assert got.preset == "paper"
    assert got.params == {
        "min_points": 6,
        "dkth_range": (0.0, 0.05),
        "merge": False,
        "max_residual": None,
    }


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (
            ["-p", "min_pts:=3"],
            "--ros-args: parameter min_pts (-p min_pts:=3): unknown; did you mean min_points? "
            "the node's parameters: method, preset, sensor_profile, topic",
        ),
        (
            ["-p", "min_points:=abc"],
            "--ros-args: parameter min_points (-p min_points:=abc): min_points must be an "
            "integer in [2, 1000000], got 'abc'",
        ),
        (["-p", "min_points:=1"], "parameter min_points (-p min_points:=1): min_points must be"),
        (["-p", "method:=nope"], "parameter method (-p method:=nope): unknown method 'nope'"),
        (["-p", "method:=3"], "parameter method (-p method:=3): a string, got 3"),
        (["-p", "preset:=fast"], "unknown preset 'fast' for method 'adaptive'"),
        (["-p", "topic:="], "parameter topic (-p topic:=): a string, got None"),
        (["-p", "topic:=''"], "parameter topic (-p topic:=''): a topic name, got an empty"),
        (["-p", "topic:=a//b"], "parameter topic (-p topic:=a//b): not a ROS 2 topic name"),
        (["-p", "use_sim_time:=1"], "parameter use_sim_time (-p use_sim_time:=1): true or false"),
        (["-p", "k:=[1"], "-p k:=[1: not a YAML value"),
    ],
)
def test_an_unknown_parameter_or_a_bad_value_names_the_parameter(words, message):
    with pytest.raises(ParameterError) as raised:
        node_options(words)
    assert message in str(raised.value)
    assert "\n" not in str(raised.value)


def test_a_method_parameter_belongs_to_the_method_set():
    got = node_options(["-p", "method:=iepf", "-p", "min_points:=5"])
    assert (got.method, got.params) == ("iepf", {"min_points": 5})
    with pytest.raises(ParameterError, match=r"parameter dkth_range .* unknown; .* method iepf's"):
        node_options(["-p", "method:=iepf", "-p", "dkth_range:=auto"])


def test_parameters_override_the_options_and_empty_strings_unset():
    given = NodeOptions(
        "adaptive", "paper", {"k": "4"}, Path("a.json"), dict(TOPICS, features_topic="f")
    )
    got = node_options(
        ["-p", "preset:=''", "-p", "sensor_profile:=''", "-p", "features_topic:=''",
         "-p", "markers_topic:=''", "-p", "topic:=front/scan", "-p", "noise_k:=2"],
        given,
    )  # fmt: skip
    assert got.preset is None
    assert got.sensor_profile is None
    assert got.params == {"k": "4", "noise_k": 2.0}
    assert got.topics == dict(TOPICS, topic="front/scan", markers_topic=None)
    untouched = node_options([], given)
    assert untouched == given


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


FILE = """
/**:
  ros__parameters:
    use_sim_time: true
    min_points: 4
scanlines:
  ros__parameters:
    method: adaptive
    min_points: 5
/robot1/scanlines:
  ros__parameters:
    min_points: 6
robot2:
  scanlines:
    ros__parameters:
      min_points: 7
/**/lines:
  ros__parameters:
    min_points: 8
/robot3/*:
  ros__parameters:
    min_points: 9
"""


@pytest.mark.parametrize(
    ("rules", "min_points"),
    [
        ([], 5),
        (["-r", "__ns:=/robot1"], 6),
        (["-r", "__ns:=/robot2"], 7),
        (["-r", "__ns:=/robot4"], 4),  # the bare name is the root namespace's node only
        (["-r", "__node:=lines"], 8),
        (["-r", "__ns:=/a/b", "-r", "__node:=lines"], 8),
        (["-r", "__ns:=/robot3", "-r", "__node:=any"], 9),
    ],
)
def test_a_files_entries_apply_to_the_nodes_their_names_match(tmp_path, rules, min_points):
    path = write(tmp_path / "params.yaml", FILE)
    got = node_options([*rules, "--params-file", str(path)])
    assert got.params == {"min_points": min_points}


def test_the_last_setting_wins_in_command_line_order(tmp_path):
    path = write(tmp_path / "p.yaml", "scanlines:\n  ros__parameters:\n    min_points: 5\n")
    after = ["-p", "min_points:=9", "--params-file", str(path)]
    before = ["--params-file", str(path), "-p", "min_points:=9"]
    assert node_options(after).params == {"min_points": 5}
    assert node_options(before).params == {"min_points": 9}
    assert node_options(["-p", "other:min_points:=7", *before[:2]]).params == {"min_points": 5}
    assert node_options(["-p", "scanlines:min_points:=7"]).params == {"min_points": 7}


def test_a_file_value_names_the_file_in_its_error(tmp_path):
    path = write(tmp_path / "p.yaml", "scanlines:\n  ros__parameters:\n    min_points: '6'\n")
    with pytest.raises(ParameterError) as raised:
        node_options(["--params-file", str(path)])
    assert str(raised.value) == (
        f"--ros-args: parameter min_points ({path}): min_points must be an integer in "
        "[2, 1000000], got '6' (a string; numbers are written without quotes)"
    )
    nested = write(tmp_path / "n.yaml", "scanlines:\n  ros__parameters:\n    a:\n      b: 1\n")
    with pytest.raises(ParameterError, match=r"parameter a\.b \(.*n\.yaml\): unknown"):
        node_options(["--params-file", str(nested)])


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("scanlines: [1, 2\n", ", line 2: not valid YAML: "),
        ("- 1\n", ": a parameters file maps node names to ros__parameters"),
        ("ros__parameters:\n  a: 1\n", ": key ros__parameters: a parameters file maps"),
        ("scanlines:\n  min_points: 3\n", ": key scanlines/min_points: a parameters file"),
        ("scanlines:\n  ros__parameters: 3\n", ": key scanlines/ros__parameters: a param"),
    ],
)
def test_a_file_that_is_no_parameters_file_is_one_line_naming_it(tmp_path, text, message):
    path = write(tmp_path / "bad.yaml", text)
    with pytest.raises(ParameterError) as raised:
        node_options(["--params-file", str(path)])
    assert str(raised.value).startswith(str(path) + message)
    assert "\n" not in str(raised.value)
    with pytest.raises(ParameterError) as missing:
        node_options(["--params-file", str(tmp_path / "missing.yaml")])
    assert str(missing.value) == f"{tmp_path / 'missing.yaml'}: no such file or directory"
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    with pytest.raises(ParameterError, match="cannot read the parameters file"):
        node_options(["--params-file", str(folder)])


def test_a_file_without_an_entry_for_the_node_says_so(tmp_path):
    path = write(tmp_path / "p.yaml", "scanlines:\n  ros__parameters:\n    min_points: 5\n")
    notes: list[str] = []
    values = parse_ros_args(["-r", "__ns:=/robot1", "--params-file", str(path)]).parameters(notes)
    assert values == {}
    assert notes == [
        f"{path}: no parameters for node /robot1/scanlines (its entries: /scanlines; in ROS 2 "
        "a bare node name is in the root namespace only: /**/NAME is in any)"
    ]
    empty = write(tmp_path / "empty.yaml", "")
    assert parse_ros_args(["--params-file", str(empty)]).parameters(notes) == {}
    assert len(notes) == 1


# -- the command -----------------------------------------------------------------------------


def test_the_command_refuses_a_bad_parameter_with_one_line_and_exit_2(tmp_path):
    done = scanlines("ros2", "--loopback", "--ros-args", "-p", "min_pts:=3")
    assert done.returncode == 2
    (line,) = done.stderr.splitlines()
    assert line.startswith("scanlines: error: --ros-args: parameter min_pts (-p min_pts:=3): ")
    done = scanlines("ros2", "--ros-args", "-r", "__ns:=relative", "--", "--loopback")
    assert done.returncode == 2
    assert done.stderr.splitlines() == [
        "scanlines: error: --ros-args: -r __ns:=relative: a namespace is absolute: it starts with /"
    ]
    done = scanlines("ros2", "--play", sample("intel"), "--ros-args", "-p", "k:=0")
    assert done.returncode == 2
    assert "parameter k (-p k:=0): k must be" in done.stderr


def test_the_help_says_what_the_sensor_profile_does_live():
    done = scanlines("ros2", "--help", columns=400)
    assert done.returncode == 0
    text = " ".join(done.stdout.split())
    assert "measured from the log" not in text
    assert "each scan's noise measured from that scan alone" in text
    assert "--ros-args" in text


# -- the shipped parameters and launch files -------------------------------------------------


def test_the_example_parameters_file_loads_through_the_nodes_parser():
    got = node_options(["--params-file", str(DOCS / "params.yaml")])
    assert got.method == "adaptive"
    assert got.params == {
        "min_points": 3,
        "min_length": 0.0,
        "dkth_range": "auto",
        "max_residual": 0.1,
    }
    assert got.topics == TOPICS  # the defaults, spelled out


class _Recorded:
    """A launch action or substitution that keeps what it was given."""

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


def _fake_launch(monkeypatch) -> None:
    """``launch`` and ``launch_ros`` as modules whose classes record their arguments."""
    names = {
        "launch": ["LaunchDescription"],
        "launch.actions": ["DeclareLaunchArgument"],
        "launch.substitutions": ["LaunchConfiguration"],
        "launch_ros": [],
        "launch_ros.actions": ["Node"],
    }
    for module_name, classes in names.items():
        module = types.ModuleType(module_name)
        for name in classes:
            setattr(module, name, type(name, (_Recorded,), {}))
        monkeypatch.setitem(sys.modules, module_name, module)


def launch_command(path: Path) -> list[str]:
    """The command line ``launch_ros.actions.Node`` builds for the launch file's node (its
    launch arguments at their defaults): executable, arguments, then ``--ros-args -r
    __node:=NAME``, ``--params-file`` for each file and ``-r FROM:=TO`` for each remapping."""
    code = compile(path.read_text(), str(path), "exec")
    namespace = {"__file__": str(path), "__name__": "launch_file"}
    exec(code, namespace)
    (actions,) = namespace["generate_launch_description"]().args
    defaults = {
        action.args[0]: action.kwargs["default_value"]
        for action in actions
        if type(action).__name__ == "DeclareLaunchArgument"
    }

    def value(item):
        return defaults[item.args[0]] if type(item).__name__ == "LaunchConfiguration" else item

    (node,) = [action for action in actions if type(action).__name__ == "Node"]
    given = node.kwargs
    assert "package" not in given  # the scanlines command, from the PATH
    command = [given["executable"], *given["arguments"], "--ros-args"]
    command += ["-r", f"__node:={given['name']}"]
    for params in given["parameters"]:
        command += ["--params-file", value(params)]
    for source, target in given["remappings"]:
        command += ["-r", f"{value(source)}:={value(target)}"]
    return command


def test_the_launch_file_runs_the_node_with_the_example_parameters(monkeypatch):
    _fake_launch(monkeypatch)
    command = launch_command(DOCS / "scanlines.launch.py")
    assert command[:3] == ["scanlines", "ros2", "--ros-args"]
    own, words = split_ros_args(command[2:])
    assert own == []
    args = parse_ros_args(words)
    assert args.fully_qualified_name == "/scanlines"
    assert [Path(p).resolve() for p in args.params_files] == [(DOCS / "params.yaml").resolve()]
    got = apply_parameters(options(), args.parameters())
    assert got == node_options(["--params-file", str(DOCS / "params.yaml")])
    assert args.resolve(got.topics["topic"]) == "/scan"


# -- the README's commands -------------------------------------------------------------------


def readme_ros2_section() -> str:
    text = (Path(__file__).parents[1] / "README.md").read_text()
    start = text.index("### Live on a robot: a ROS 2 node")
    return text[start : text.index("\n### ", start + 1)]


def test_the_readmes_ros_commands_parse_and_its_start_line_is_the_nodes():
    import re
    import shlex

    from scanlines.cli.ros2 import start_line
    from scanlines.extractor import Extractor

    section = readme_ros2_section()
    commands = re.search(r"```bash\n(.*?)```", section, flags=re.DOTALL).group(1)
    ros_lines = [line for line in commands.splitlines() if "--ros-args" in line]
    assert len(ros_lines) >= 2
    root = Path(__file__).parents[1]
    for line in ros_lines:
        words = shlex.split(line, comments=True)
        assert words[:2] == ["scanlines", "ros2"]
        _, ros_words = split_ros_args(words[2:])
        ros_words = [str(root / w) if w.endswith(".yaml") else w for w in ros_words]
        args = parse_ros_args(ros_words)
        got = apply_parameters(options(), args.parameters())
        if "__ns:=/robot1" in line:
            topics = {k: None if v is None else args.resolve(v) for k, v in got.topics.items()}
            extractor = Extractor(got.method, got.preset, **got.params)
            shown = start_line(args.fully_qualified_name, 0, extractor, got, None, topics)
            (example,) = re.findall(r"^scanlines ros2: node .*$", section, flags=re.MULTILINE)
            assert shown == example
    assert "ros2 launch docs/ros2/scanlines.launch.py" in commands


def test_amcls_frame_parameters_and_the_map_set_the_live_localisation():
    given = NodeOptions(
        "adaptive",
        live={"map": None, "odometry": "odom", "global_frame_id": "map",
              "odom_frame_id": "odom", "base_frame_id": "base_link"},
    )  # fmt: skip
    chosen = node_options(
        ["-p", "map:=/maps/lab.json", "-p", "base_frame_id:=base_footprint", "-p",
         "odometry:=tf"],
        given,
    )  # fmt: skip
    assert chosen.live == {"map": "/maps/lab.json", "odometry": "tf", "global_frame_id": "map",
                           "odom_frame_id": "odom", "base_frame_id": "base_footprint"}  # fmt: skip
    assert node_options(["-p", "map:=''"], chosen).live["map"] is None
    with pytest.raises(ParameterError, match=r"parameter odometry \(-p odometry:=wheels\): "):
        node_options(["-p", "odometry:=wheels"], given)
    with pytest.raises(ParameterError, match=r"parameter odom_frame_id .*empty string"):
        node_options(["-p", "odom_frame_id:=''"], given)
