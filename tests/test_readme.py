"""The README's Python snippets run as written, in order, in one namespace."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).parents[1] / "README.md"


def python_snippets() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.DOTALL)


def test_the_readme_snippets_run(capsys) -> None:
    snippets = python_snippets()
    assert len(snippets) >= 2
    namespace: dict = {}
    for snippet in snippets:
        exec(compile(snippet, str(README), "exec"), namespace)
    printed = capsys.readouterr().out
    assert printed.count("\n") >= 4
    assert "corner" in printed or "jump" in printed or "edge" in printed


def test_the_library_snippet_builds_what_it_says() -> None:
    """A wall ahead and two side walls: three segments meeting at two corners, as the
    snippet's comment says; its closing comment's call runs as written."""
    snippet = python_snippets()[0]
    assert "a wall 2 m ahead, side walls 1.5 m away" in snippet
    assert "3 segments, 2 corners" in snippet
    namespace: dict = {}
    exec(compile(snippet, str(README), "exec"), namespace)
    result = namespace["result"]
    assert len(result.segments) == 3
    assert len(result.corners) == 2
    (call,) = re.findall(r"print\((method_info\([^)]*\))\)", snippet)
    assert eval(call, namespace).name == "adaptive"


def fleet_section() -> str:
    text = README.read_text()
    start = text.index("### Many logs: a Parquet dataset")
    return text[start : text.index("\n### ", start + 1)]


def test_the_parquet_query_reads_what_the_commands_write() -> None:
    section = fleet_section()
    commands = re.search(r"```bash\n(.*?)```", section, flags=re.DOTALL).group(1)
    outputs = set(re.findall(r"--out (\S+)", commands))
    (query_path,) = re.findall(r"read_parquet\('([^']+)'", section)
    assert outputs == {query_path.split("/", 1)[0]}
    assert all("--format parquet" in line for line in commands.splitlines()[1:] if line)


def test_extras_are_installed_from_a_checkout() -> None:
    """scanlines is not on the package index: ``pip install "scanlines[...]"`` cannot work."""
    assert 'pip install "scanlines[' not in README.read_text()


def test_the_live_ros_hint_names_the_sensor_profile() -> None:
    """The one-line hint for live users leads to the extraction ``run`` does, with the
    sensor's profile, not to a bare ``extract`` without a word about the difference."""
    text = re.sub(r"\s+", " ", README.read_text())
    hint = text[text.index("Live ROS users") :][:700]
    assert "Scan.from_laserscan(msg)" in hint
    assert "Extractor(sensor_profile=" in hint
    assert "scanlines calibrate" in hint
