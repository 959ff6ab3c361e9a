"""ROS 2 names as rcl resolves them: a topic name under the node's namespace, then remapped.

A relative name (``scan``) lives under the node's namespace (``/robot1/scan`` under
``/robot1``), an absolute one (``/tf``) stays, a private one (``~/lines``) lives under the
node (``/robot1/scanlines/lines``); ``{node}`` and ``{ns}`` are substituted. A remapping
rule ``from:=to`` replaces a name whose expansion is ``from``'s expansion by ``to``'s; the
first rule that matches wins, as in rcl, and a rule ``node:from:=to`` applies to that node
only.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from scanlines.errors import ParameterError
from scanlines.untrusted import quote

__all__ = ["Remap", "expand", "namespace_problem", "node_name_problem", "resolve"]

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


@dataclass(frozen=True)
class Remap:
    """One rule ``[node:]source:=target`` of ``-r``."""

    source: str
    target: str
    node: str | None = None

    def __str__(self) -> str:
        prefix = "" if self.node is None else f"{self.node}:"
        return f"{prefix}{self.source}:={self.target}"


def node_name_problem(name: str) -> str | None:
    """Why ``name`` is no ROS 2 node name (letters, digits and ``_``, not starting with a
    digit), or ``None``."""
    if not _TOKEN.match(name):
        return "a node name is letters, digits and _, not starting with a digit"
    return None


def namespace_problem(namespace: str) -> str | None:
    """Why ``namespace`` is no absolute ROS 2 namespace (``/`` or ``/a/b``), or ``None``."""
    if not namespace.startswith("/"):
        return "a namespace is absolute: it starts with /"
    if namespace == "/":
        return None
    return _tokens_problem(namespace[1:])


def _tokens_problem(path: str) -> str | None:
    for token in path.split("/"):
        if not token:
            return "it has an empty token (// or a trailing /)"
        if not _TOKEN.match(token):
            return f"token {quote(token)} is not letters, digits and _, not starting with a digit"
    return None


def expand(name: str, node: str, namespace: str) -> str:
    """The fully qualified name of topic ``name`` of node ``node`` in ``namespace``.

    Raises
    ------
    ParameterError
        For a name that is not a valid ROS 2 topic name (the message quotes it).
    """
    expanded = name.replace("{node}", node).replace("{ns}", namespace)
    expanded = expanded.replace("{namespace}", namespace)
    base = namespace.rstrip("/")
    if "{" in expanded or "}" in expanded:
        problem = "substitutions are {node}, {ns} and {namespace}"
    elif expanded.startswith("~"):
        rest = expanded[1:]
        problem = None if not rest or rest.startswith("/") else "~ is followed by / or nothing"
        expanded = f"{base}/{node}{rest}"
    elif not expanded.startswith("/"):
        expanded = f"{base}/{expanded}"
        problem = None
    else:
        problem = None
    if problem is None:
        problem = _tokens_problem(expanded[1:]) if expanded != "/" else "it names no topic"
    if problem is not None:
        raise ParameterError(f"not a ROS 2 topic name: {quote(name)} ({problem})")
    return expanded


def resolve(name: str, remaps: list[Remap], node: str, namespace: str) -> str:
    """``name`` expanded (:func:`expand`) and remapped by the first rule of ``remaps``
    that matches it."""
    expanded = expand(name, node, namespace)
    for rule in remaps:
        if rule.node is not None and rule.node != node:
            continue
        if expand(rule.source, node, namespace) == expanded:
            return expand(rule.target, node, namespace)
    return expanded
