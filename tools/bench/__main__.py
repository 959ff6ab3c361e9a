"""``python -m tools.bench [--out PAGE] [scanlines bench options]``: time every method with
``scanlines bench`` (adaptive profiled too) and write the page, ``docs/PERFORMANCE.md`` by
default."""

from __future__ import annotations

import sys
from pathlib import Path

from scanlines.bench.results import BenchResult
from scanlines.report import command_line
from tools.bench.performance_page import write_docs

DEFAULT_PAGE = Path("docs/PERFORMANCE.md")


def main(argv: list[str]) -> int:
    from scanlines.cli.commands import app

    page, options = DEFAULT_PAGE, list(argv)
    if "--out" in options:
        at = options.index("--out")
        page = Path(options[at + 1])
        del options[at : at + 2]
    result = app(["bench", "--profile", *options], prog_name="scanlines", standalone_mode=False)
    if not isinstance(result, BenchResult):  # --help, or an error already said
        return int(result or 0)
    result.command = command_line(argv, program="python -m tools.bench")
    print(f"wrote {write_docs(result, page)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
