"""The ROS arguments a ROS 2 node takes after ``--ros-args``, read as rcl reads them.

``scanlines ros2 ... --ros-args -r scan:=/front/scan -r __ns:=/robot1 -p method:=iepf
--params-file params.yaml``: ``-r``/``--remap`` rules (``__node:=`` and ``__ns:=`` rename
the node and set its namespace), ``-p``/``--param`` ``name:=value`` (the value read as
YAML, as ROS does: ``6`` is an integer, ``[0.0, 0.05]`` a list) and ``--params-file``
(``node: ros__parameters: {...}``). A section runs to ``--`` or to the end of the command
line; the words outside every section are the command's own. The log flags that launch
files add (``--log-level``...) are accepted and have no effect.

Parameters apply in the order given, the last one winning; a file's entries apply when
their node name matches the node's fully qualified name as ROS 2 matches it: ``scanlines``
(or ``/scanlines``) is the node ``scanlines`` in the root namespace only; ``/robot1/
scanlines``, nested ``robot1: scanlines:``, ``/**/scanlines`` (any namespace), ``/**``
(every node) and ``*`` (one token) name others.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from scanlines.errors import NO_SUCH_FILE, ParameterError
from scanlines.ros2.names import Remap, expand, namespace_problem, node_name_problem
from scanlines.untrusted import UntrustedInput, clip, load_yaml, quote, read_regular_file

__all__ = [
    "DEFAULT_NODE_NAME",
    "Parameter",
    "RosArgs",
    "parse_ros_args",
    "split_ros_args",
]

#: The node's name unless ``-r __node:=NAME`` renames it.
DEFAULT_NODE_NAME = "scanlines"
#: Largest parameters file read.
MAX_FILE_BYTES = 1 << 20
#: rcl's flags without an effect here: taking a value, and alone.
_IGNORED_WITH_VALUE = ("--log-level", "--log-config-file")
_IGNORED_FLAGS = tuple(
    f"--{state}-{what}-logs"
    for state in ("enable", "disable")
    for what in ("rosout", "stdout", "external-lib")
)


def split_ros_args(argv: Iterable[str]) -> tuple[list[str], list[str] | None]:
    """``argv`` as the command's own words and the words of its ``--ros-args`` sections
    (``None`` when there is none): each section runs to ``--`` or to the end."""
    own: list[str] = []
    ros: list[str] = []
    inside = seen = False
    for word in argv:
        if word == "--ros-args":
            inside = seen = True
        elif inside and word == "--":
            inside = False
        else:
            (ros if inside else own).append(word)
    return own, ros if seen else None


@dataclass(frozen=True)
class Parameter:
    """A parameter's value as ROS typed it, and where it was set: ``-p NAME:=VALUE`` or
    the parameters file."""

    value: Any
    origin: str


@dataclass
class RosArgs:
    """What ``--ros-args`` said: remapping rules, the node's name and namespace, and the
    parameter sources in order (``("-p", (node, name, text))`` or ``("file", path)``)."""

    remaps: list[Remap] = field(default_factory=list)
    node: str = DEFAULT_NODE_NAME
    namespace: str = "/"
    sources: list[tuple[str, Any]] = field(default_factory=list)

    @property
    def fully_qualified_name(self) -> str:
        """``/namespace/node``."""
        return f"{self.namespace.rstrip('/')}/{self.node}"

    @property
    def params_files(self) -> list[Path]:
        return [path for kind, path in self.sources if kind == "file"]

    def resolve(self, name: str) -> str:
        """Topic ``name`` expanded under the node's namespace and remapped."""
        from scanlines.ros2.names import resolve

        return resolve(name, self.remaps, self.node, self.namespace)

    def parameters(self, notes: list[str] | None = None) -> dict[str, Parameter]:
        """Every parameter set for this node, by name, the last setting of each winning.
        ``notes`` gets a line for each parameters file with no entry for the node.

        Raises
        ------
        ParameterError
            For a parameters file that cannot be read or is no parameters file, or a
            ``-p`` value that is not YAML (one line naming the file or the parameter).
        """
        values: dict[str, Parameter] = {}
        for kind, source in self.sources:
            if kind == "file":
                found, entries = file_parameters(source, self.fully_qualified_name)
                for name, value in found:
                    values[name] = Parameter(value, str(source))
                if notes is not None and entries and not found:
                    notes.append(
                        f"{source}: no parameters for node {self.fully_qualified_name} (its "
                        f"entries: {', '.join(entries)}; in ROS 2 a bare node name is in the "
                        "root namespace only: /**/NAME is in any)"
                    )
            else:
                node, name, text = source
                if node is None or node == self.node:
                    origin = f"-p {clip(name)}:={clip(text)}"
                    values[name] = Parameter(_yaml_value(name, text), origin)
        return values


def _rule(flag: str, text: str) -> tuple[str | None, str, str]:
    """``[node:]name:=value`` as its three parts."""
    left, sep, value = text.partition(":=")
    if not sep or not left:
        raise ParameterError(f"--ros-args: {flag} takes [node:]NAME:=VALUE, got {quote(text)}")
    node, colon, name = left.rpartition(":")
    return (node if colon else None), name, value


def parse_ros_args(words: list[str]) -> RosArgs:
    """The words of the ``--ros-args`` sections (:func:`split_ros_args`) read; parameters
    files are read by :meth:`RosArgs.parameters`.

    Raises
    ------
    ParameterError
        One line for a flag without its value, an unknown flag, a rule that is no
        ``NAME:=VALUE``, or a node name, namespace or topic name ROS 2 refuses.
    """
    args = RosArgs()
    node = namespace = None
    remaps: list[Remap] = []
    queue = list(words)
    while queue:
        flag = queue.pop(0)
        if flag in _IGNORED_FLAGS:
            continue
        takes_value = ("-r", "--remap", "-p", "--param", "--params-file", *_IGNORED_WITH_VALUE)
        if flag not in takes_value:
            raise ParameterError(
                f"--ros-args: unknown argument {quote(flag)}; this node takes -r/--remap FROM:=TO, "
                "-p/--param NAME:=VALUE and --params-file FILE (a section ends at --)"
            )
        if not queue:
            raise ParameterError(f"--ros-args: {flag} needs a value")
        value = queue.pop(0)
        if flag in ("-r", "--remap"):
            prefix, source, target = _rule(flag, value)
            if source in ("__node", "__name"):
                node = node or target  # the first rule wins, as in rcl
            elif source == "__ns":
                namespace = namespace or target
            else:
                remaps.append(Remap(source, target, prefix))
        elif flag in ("-p", "--param"):
            args.sources.append(("-p", _rule(flag, value)))
        elif flag == "--params-file":
            args.sources.append(("file", Path(value)))
    if node is not None:
        problem = node_name_problem(node)
        if problem:
            raise ParameterError(f"--ros-args: -r __node:={node}: {problem}")
        args.node = node
    if namespace is not None:
        problem = namespace_problem(namespace)
        if problem:
            raise ParameterError(f"--ros-args: -r __ns:={namespace}: {problem}")
        args.namespace = namespace
    for rule in remaps:
        for name in (rule.source, rule.target):
            try:
                expand(name, args.node, args.namespace)
            except ParameterError as error:
                raise ParameterError(f"--ros-args: -r {rule}: {error}") from None
    args.remaps = remaps
    return args


def _yaml_value(name: str, text: str) -> Any:
    """A ``-p`` value read as YAML, at a bounded cost (:func:`~scanlines.untrusted.load_yaml`)."""
    import yaml

    try:
        return load_yaml(text)
    except UntrustedInput as error:
        raise ParameterError(
            f"--ros-args: -p {clip(name)}:={clip(text)}: refused: {error}"
        ) from None
    except yaml.YAMLError as error:
        reason = clip(" ".join(str(error).split()), 160)
        raise ParameterError(
            f"--ros-args: -p {clip(name)}:={clip(text)}: not a YAML value: {reason}"
        ) from None


def file_parameters(path: Path, node: str) -> tuple[list[tuple[str, Any]], list[str]]:
    """The parameters of ``node`` (fully qualified) in the parameters file ``path``, in
    the file's order, and the node names the file has entries for.

    Raises
    ------
    ParameterError
        One line naming the file: missing, unreadable, too large, not YAML (with its line),
        or not laid out as ``node: ros__parameters: {name: value}``.
    """
    import yaml

    try:
        data = read_regular_file(path, MAX_FILE_BYTES)
    except FileNotFoundError:
        raise ParameterError(f"{path}: {NO_SUCH_FILE}") from None
    except OSError as error:
        raise ParameterError(f"{path}: cannot read the parameters file: {error.strerror}") from None
    except UntrustedInput as error:
        raise ParameterError(f"{path}: {error}; not a parameters file") from None
    try:
        document = load_yaml(data)
    except UntrustedInput as error:
        raise ParameterError(f"{path}: refused: {error}") from None
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = "" if mark is None else f", line {mark.line + 1}"
        reason = getattr(error, "problem", None) or " ".join(str(error).split())
        raise ParameterError(f"{path}{where}: not valid YAML: {clip(reason, 160)}") from None
    if document is None:
        return [], []
    if not isinstance(document, Mapping):
        raise ParameterError(f"{path}: {_LAYOUT}")
    found: list[tuple[str, Any]] = []
    entries: list[str] = []
    _walk(path, document, [], node, found, entries)
    return found, entries


_LAYOUT = "a parameters file maps node names to ros__parameters: NAME: VALUE"


def _walk(
    path: Path,
    mapping: Mapping,
    keys: list[str],
    node: str,
    found: list[tuple[str, Any]],
    entries: list[str],
) -> None:
    for key, value in mapping.items():
        if key == "ros__parameters":
            pattern = "/" + "/".join(k.strip("/") for k in keys)
            entries.append(pattern)
            if not keys or not isinstance(value, Mapping):
                raise ParameterError(f"{path}: key {clip('/'.join([*keys, key]))}: {_LAYOUT}")
            if _node_pattern(pattern).match(node):
                found.extend(_flattened(path, value, ""))
        elif isinstance(value, Mapping):
            _walk(path, value, [*keys, str(key)], node, found, entries)
        else:
            raise ParameterError(f"{path}: key {clip('/'.join([*keys, str(key)]))}: {_LAYOUT}")


def _node_pattern(pattern: str) -> re.Pattern:
    """The node names a file's key matches: ``**`` any tokens (none too), ``*`` any
    characters of one token."""
    parts = []
    for token in pattern.strip("/").split("/"):
        if token == "**":
            parts.append("(?:/[^/]+)*")
        else:
            parts.append("/" + re.escape(token).replace(r"\*", "[^/]*"))
    return re.compile("".join(parts) + r"\Z")


def _flattened(path: Path, mapping: Mapping, prefix: str) -> list[tuple[str, Any]]:
    """``{a: {b: 1}}`` as ``[("a.b", 1)]``, as ROS 2 names nested parameters."""
    out: list[tuple[str, Any]] = []
    for key, value in mapping.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.extend(_flattened(path, value, f"{name}."))
        else:
            out.append((name, value))
    return out
