"""CI's scripts run what they say: the README's test command, and the sanitizer lane's tests."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

ROOT = Path(__file__).parents[1]


def test_ci_runs_the_readmes_test_command() -> None:
    readme = (ROOT / "README.md").read_text()
    ci_run = (ROOT / ".ci" / "run").read_text()
    command = 'pip install -e ".[dev]" && python -m pytest'
    assert command in readme
    assert command in ci_run


def test_every_test_path_of_the_sanitizer_lane_exists() -> None:
    """With two workers, pytest reports a missing path as 'no tests ran' (exit 5), not as
    the missing file: a moved test file would silently empty the lane."""
    script = (ROOT / ".ci" / "sanitize").read_text()
    (call,) = re.findall(r'"\$py" -m pytest (.*?)\|\| status', script, flags=re.DOTALL)
    paths = [word for word in shlex.split(call.replace("\\\n", " ")) if word.startswith("tests")]
    assert len(paths) >= 5
    missing = [path for path in paths if not (ROOT / path).exists()]
    assert missing == []
