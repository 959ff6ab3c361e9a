"""Record the files ``scanlines map`` and ``scanlines localize`` write for the shipped excerpts,
or check that this checkout writes the recorded ones byte for byte.

    python tools/benchmarks/same_map_outputs.py record map_outputs.json
    python tools/benchmarks/same_map_outputs.py compare map_outputs.json

For a change that must not change a map, a trajectory or a covariance (a re-housing of
``map/`` or of the filter's kernel): record with the version before the change, then compare
with the version after. ``tests/records/map_outputs.json`` is such a record (the SHA-256 of
each file), and ``tests/test_same_map_outputs.py`` compares against it on every test run.

The runs (:data:`RUNS`, in this order, in one directory): the Intel excerpt mapped at its
log's poses; Intel tracked (``map --align``) with and without its loops closed, and URG with
them; Intel localised on the plain and the tracked map from the tracked poses' first
(``--initial-pose-from``, also with ``--sides``) and from no pose (global localisation). A
loop-closing run's JSON says how long its pose graph took (``"seconds"``): that field is
left out. ``map --align`` sums its normal matrices with numpy's matrix product, whose order
is the BLAS build's: another BLAS may move the last digits of its covariances.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import sys
import tempfile
from pathlib import Path

from scanlines.data import sample

#: Each run's arguments, ``{intel}`` and ``{urg}`` the shipped excerpts.
RUNS = (
    ("map", "{intel}", "--out", "intel_map.json"),
    ("map", "{intel}", "--align", "--out", "intel_align.json", "--poses-out", "intel_align.tum"),
    ("map", "{intel}", "--align", "--no-loops", "--out", "intel_align_nl.json",
     "--poses-out", "intel_align_nl.tum"),
    ("map", "{urg}", "--align", "--out", "urg_align.json", "--poses-out", "urg_align.tum"),
    ("localize", "{intel}", "--map", "intel_map.json", "--initial-pose-from",
     "intel_align_nl.tum", "--out", "loc_from.tum"),
    ("localize", "{intel}", "--map", "intel_align_nl.json", "--initial-pose-from",
     "intel_align_nl.tum", "--out", "loc_from_aligned.tum"),
    ("localize", "{intel}", "--map", "intel_align_nl.json", "--initial-pose-from",
     "intel_align_nl.tum", "--sides", "--out", "loc_sides.tum"),
    ("localize", "{intel}", "--map", "intel_map.json", "--out", "loc_global.tum"),
    ("localize", "{intel}", "--map", "intel_align_nl.json", "--out", "loc_global_aligned.tum"),
)  # fmt: skip
_SECONDS = re.compile(rb'"seconds": [-+0-9.eE]+')


def run(directory: Path) -> None:
    """Every run of :data:`RUNS` in ``directory`` (the command line in this process)."""
    sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))
    from cli_helpers import scanlines

    logs = {"intel": sample("intel"), "urg": sample("urg")}
    for args in RUNS:
        ran = scanlines(*(a.format(**logs) for a in args), cwd=directory)
        if ran.returncode != 0:
            raise RuntimeError(f"scanlines {' '.join(args)}: exit {ran.returncode}\n{ran.stderr}")


def digests(directory: Path) -> dict[str, str]:
    """The SHA-256 of every file in ``directory`` by name, ``"seconds"`` fields left out."""
    return {
        path.name: hashlib.sha256(_SECONDS.sub(b'"seconds": -', path.read_bytes())).hexdigest()
        for path in sorted(directory.iterdir())
    }


def current() -> dict[str, str]:
    """The digests of this checkout's files."""
    with tempfile.TemporaryDirectory() as directory:
        run(Path(directory))
        return digests(Path(directory))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("record", "compare"))
    parser.add_argument("path")
    args = parser.parse_args()
    found = current()
    if args.action == "record":
        Path(args.path).write_text(json.dumps(found, indent=1) + "\n")
        print(f"recorded {len(found)} files")
        return
    recorded = json.loads(Path(args.path).read_text())
    differ = sorted(n for n in recorded.keys() | found.keys() if recorded.get(n) != found.get(n))
    print(f"{len(differ)} files differ of {len(recorded)}" + "".join(f"\n  {n}" for n in differ))
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
