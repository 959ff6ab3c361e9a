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


def chain_section() -> str:
    text = README.read_text()
    start = text.index("### From a raw log to a map and a trajectory")
    return text[start : text.index("\n## ", start)]


def test_the_raw_log_to_trajectory_section_runs_as_written(tmp_path) -> None:
    """The section's commands, as a new user pastes them into a shell in an empty folder,
    on the shipped sample; what the text says of their results is what they print."""
    import json
    import os
    import subprocess
    import sys

    section = chain_section()
    (commands,) = re.findall(r"```bash\n(.*?)```", section, flags=re.DOTALL)
    assert "scanlines sample intel" in commands
    assert "--initial-pose-from est.tum" in commands
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    done = subprocess.run(["bash", "-euo", "pipefail", "-c", commands], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    written = {p.name for p in tmp_path.iterdir()}
    assert {"intel.json", "est.tum", "loc.tum", "loc_vs_map.json", "odom_vs_map.json"} <= written
    text = re.sub(r"\s+", " ", section)
    lines = re.search(r"(\d+) map lines from ([\d,]+) segments", done.stdout)
    assert f"{lines.group(1)} map lines from {lines.group(2)} segments" in text.replace(",", "")
    localised = json.loads((tmp_path / "loc_vs_map.json").read_text())
    odometry = json.loads((tmp_path / "odom_vs_map.json").read_text())
    assert localised["matched"] == 300
    assert f"ATE RMSE of {1000 * localised['ate_rmse']:.1f} mm" in text
    assert f"raw odometry {1000 * odometry['ate_rmse']:.1f} mm" in text


def test_no_example_names_a_log_it_does_not_qualify() -> None:
    """The logs the README's examples name that are not shipped are said not to be."""
    text = README.read_text()
    assert "intel_raw.clf.gz" not in text
    for name in ("intel-corrected.log.gz", "fr079.log.gz"):
        first = text.index(name)
        said = text[max(0, first - 1500) : first + 1500]
        assert "not shipped" in said, name


def test_the_provenance_lists_every_shipped_excerpt() -> None:
    """PROVENANCE.md's table names each sample with its file's size and sha256."""
    import hashlib
    import re

    from scanlines.data import SAMPLES, provenance, sample

    text = provenance()
    assert text.count('| `"') == len(SAMPLES) == 3
    assert "Three short excerpts" in text
    for name, file_name in SAMPLES.items():
        data = sample(name).read_bytes()
        row = re.search(rf'^\| `"{name}"` \| `{re.escape(file_name)}` \| ([\d,]+) B.*$', text, re.M)
        assert row is not None, name
        assert int(row.group(1).replace(",", "")) == len(data)
        assert hashlib.sha256(data).hexdigest() in row.group(0)
