"""A line map against where the world's origin is: the shipped excerpts shifted by a constant.

    python tools/benchmarks/map_offsets.py [--log intel] [--offsets 0 1e4 1e5 5e6 1e7 1e8 1e9]

Writes the excerpt with every pose moved by the offset in x and in y (``FLASER`` laser and
robot poses, ``ODOM``), then runs ``scanlines map LOG --out map.json`` and ``scanlines
eval --map LOG --out DIR`` on it, each in a fresh process, and prints per offset: the
exit code, the map's lines, the largest distance of a line's ends from the unshifted
map's after removing the offset, the held-out coverage, the seconds of ``map``, and the
last stderr line of a refusal. The same trajectory should give the same map and score at
every offset the map takes, and a one-line refusal beyond.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from map_shift import shifted_sample


def run(args: list[str]) -> tuple[int, str, float]:
    started = time.perf_counter()
    command = [sys.executable, "-m", "scanlines", *args]
    done = subprocess.run(command, capture_output=True, text=True)
    return done.returncode, done.stderr, time.perf_counter() - started


def ends(path: Path):
    import numpy as np

    lines = json.loads(path.read_text())["lines"]
    return np.array([[line["start"], line["end"]] for line in lines])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("--log", default="intel", choices=("intel", "freiburg"))
    parser.add_argument(
        "--offsets", type=float, nargs="+", default=[0, 1e4, 1e5, 5e6, 1e7, 1e8, 1e9]
    )
    args = parser.parse_args(argv)
    print("| offset, m | exit | map lines | ends vs offset 0, m | coverage | map, s | refusal |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        reference = None
        for offset in args.offsets:
            log = shifted_sample(args.log, offset, folder)
            out = folder / f"map-{offset:g}.json"
            code, stderr, seconds = run(["map", str(log), "--out", str(out)])
            scored = folder / f"eval-{offset:g}"
            run(["eval", "map", str(log), "--out", str(scored)])
            lines, difference, coverage, refusal = "-", "-", "-", ""
            if code == 0:
                mine = ends(out)
                lines = str(len(mine))
                if reference is None:
                    reference = mine
                if mine.shape == reference.shape:
                    difference = f"{abs(mine - offset - reference).max():.1e}"
                score = json.loads((scored / "map_eval.json").read_text())
                coverage = f"{score['coverage']:.3f}"
            else:
                refusal = stderr.strip().splitlines()[-1].replace(str(folder) + "/", "")
            print(
                f"| {offset:g} | {code} | {lines} | {difference} | {coverage} | {seconds:.1f} "
                f"| {refusal} |"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
