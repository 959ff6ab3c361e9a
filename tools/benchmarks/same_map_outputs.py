"""Record the files ``scanlines map`` and ``scanlines localize`` write for the shipped excerpts,
or check that this checkout writes the recorded ones byte for byte.

    python tools/benchmarks/same_map_outputs.py record map_outputs.json
    python tools/benchmarks/same_map_outputs.py compare map_outputs.json

For a change that must not change a map, a trajectory or a covariance (a re-housing of
``map/`` or of the filter's kernel): record with the version before the change, then compare
with the version after. ``tests/records/map_outputs.json`` is such a record (the SHA-256 of
each file), and ``tests/map/test_same_map_outputs.py`` compares against it on every test run.

The runs (:data:`RUNS`, in this order, in one directory): the Intel excerpt mapped at its
log's poses; Intel tracked (``map --align``) with and without its loops closed, and URG with
them; Intel localised on the plain and the tracked map from the tracked poses' first
(``--initial-pose-from``, also with ``--sides``) and from no pose (global localisation);
Intel mapped with ``--min-scans 2``; ``eval map`` with and without ``--align``. A
loop-closing run's JSON says how long its pose graph took (``"seconds"``): that field is
left out. ``map --align`` sums its normal matrices with numpy's matrix product, whose order
is the BLAS build's: another BLAS may move the last digits of its covariances, so a
record keeps each file's SHA-256 (``compare`` asks for the same bytes) and, beside it in a
``.npz``, its numbers (the test asks for them to a relative 1e-9, and for the text between
them exactly).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

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
    ("map", "{intel}", "--out", "intel_min2.json", "--min-scans", "2"),
    ("eval", "map", "{intel}", "--align", "--out", "eval_aligned"),
    ("eval", "map", "{intel}", "--out", "eval_given"),
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


_NUMBER = re.compile(rb"-?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def numbers(data: bytes) -> np.ndarray:
    """Every number of a file's text, in order (``"seconds"`` fields left out)."""
    return np.array(
        [float(n) for n in _NUMBER.findall(_SECONDS.sub(b'"seconds": -', data))], dtype=float
    )


def digest(data: bytes) -> dict[str, str]:
    """A file's SHA-256 and the SHA-256 of its text with every number replaced by ``#``
    (``"seconds"`` fields left out of both)."""
    data = _SECONDS.sub(b'"seconds": -', data)
    return {
        "sha256": hashlib.sha256(data).hexdigest(),
        "text": hashlib.sha256(_NUMBER.sub(b"#", data)).hexdigest(),
    }


def current() -> tuple[dict[str, dict[str, str]], dict[str, np.ndarray]]:
    """This checkout's files: their digests and their numbers, by name."""
    with tempfile.TemporaryDirectory() as directory:
        run(Path(directory))
        files = {
            path.relative_to(directory).as_posix(): path.read_bytes()
            for path in sorted(Path(directory).rglob("*"))
            if path.is_file()
        }
    return (
        {name: digest(data) for name, data in files.items()},
        {name: numbers(data) for name, data in files.items()},
    )


def beyond_rounding(
    recorded: tuple[dict, dict], found: tuple[dict, dict], rtol: float = 1e-9
) -> list[str]:
    """The files whose text between the numbers differs, or one of whose numbers differs
    by more than ``rtol`` of itself: what another BLAS's order of summation (the last
    digits of ``map --align``'s covariances) does not explain."""
    (texts, values), (found_texts, found_values) = recorded, found
    return sorted(
        name
        for name in texts.keys() | found_texts.keys()
        if texts.get(name, {}).get("text") != found_texts.get(name, {}).get("text")
        or values[name].shape != found_values[name].shape
        or not np.allclose(values[name], found_values[name], rtol=rtol, atol=1e-15)
    )


def read_record(path: Path) -> tuple[dict, dict]:
    """A record: the digests (``path``, JSON) and the numbers (beside it, ``.npz``)."""
    with np.load(path.with_suffix(".npz")) as values:
        return json.loads(path.read_text()), dict(values)


def write_record(path: Path, found: tuple[dict, dict]) -> None:
    path.write_text(json.dumps(found[0], indent=1) + "\n")
    np.savez_compressed(path.with_suffix(".npz"), **found[1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("record", "compare"))
    parser.add_argument("path")
    args = parser.parse_args()
    path = Path(args.path)
    found = current()
    if args.action == "record":
        write_record(path, found)
        print(f"recorded {len(found[0])} files")
        return
    recorded = read_record(path)
    names = sorted(recorded[0].keys() | found[0].keys())
    sha = [(recorded[0].get(n, {}).get("sha256"), found[0].get(n, {}).get("sha256")) for n in names]
    bytes_differ = [n for n, (old, new) in zip(names, sha, strict=True) if old != new]
    differ = beyond_rounding(recorded, found)
    print(
        f"{len(bytes_differ)} of {len(names)} files differ in their bytes"
        + "".join(f"\n  {n}" for n in bytes_differ)
    )
    print(f"{len(differ)} differ beyond rounding" + "".join(f"\n  {n}" for n in differ))
    sys.exit(1 if bytes_differ else 0)


if __name__ == "__main__":
    main()
