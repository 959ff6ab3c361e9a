"""Files that set things, made hostile: each run through its command in a process of its own.

    python tools/benchmarks/hostile_inputs.py [--memory-gb 3] [--timeout 60]

Writes a parameters file of nested aliases (414 bytes), a recursive alias, 100 KB of ``[``
(as ``-p``, in a parameters file, in a ``--config`` TOML), ``-p`` with 5,000 digits, a
sensor profile with a noise of 1e300, and line maps made from the shipped Intel excerpt's
(lines at 1e308, ``frame.origin`` NaN, a 100,000-deep JSON, every ``rho`` at 1e308, a
negative covariance and a boolean coordinate); names ``/dev/zero`` as a profile; and asks
``hough`` for ``rho_resolution=5e-324``. Each command runs in a fresh process whose address
space is limited (``--memory-gb``) and prints: the exit code, the seconds, the size of
stderr and its last line. Every one should exit 2 with one line.
"""

from __future__ import annotations

import argparse
import gzip
import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from scanlines.data import sample


def alias_bomb(levels: int = 8) -> str:
    """A parameters file whose ``min_points`` stands for 9**levels strings."""
    rows = ['    a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    names = "abcdefghij"
    for k in range(1, levels):
        rows.append(f"    {names[k]}: &{names[k]} [{','.join(['*' + names[k - 1]] * 9)}]")
    tail = f"scanlines:\n  ros__parameters:\n    min_points: *{names[levels - 1]}\n"
    return "other:\n  ros__parameters:\n" + "\n".join(rows) + "\n" + tail


def write_files(folder: Path, log: str) -> None:
    (folder / "bomb.yaml").write_text(alias_bomb())
    (folder / "recursive.yaml").write_text("scanlines:\n  ros__parameters: &a\n    nested: *a\n")
    (folder / "deep.yaml").write_text("scanlines:\n  ros__parameters:\n    k: " + "[" * 100_000)
    (folder / "deep.toml").write_text("method = 'iepf'\n[params]\nmin_points = " + "[" * 100_000)
    noise = {"format": "scanlines-sensor-profile/1", "noise_sigma0": 1e300, "noise_per_metre": 0}
    (folder / "noise.json").write_text(json.dumps(noise))
    subprocess.run(
        [sys.executable, "-m", "scanlines", "map", log, "--out", str(folder / "map.json")],
        capture_output=True,
        check=True,
    )
    good = (folder / "map.json").read_text()
    changes = {
        "far.json": lambda m: m["lines"][0].update(start=[1e308, 1e308]),
        "nan.json": lambda m: m["frame"].update(origin=[math.nan, 0.0]),
        "rho.json": lambda m: [line.update(rho=1e308) for line in m["lines"]],
        "cov.json": lambda m: m["lines"][0].update(covariance=[[-1.0, 0.0], [0.0, 1.0]]),
        "bool.json": lambda m: m["lines"][1].update(start=[True, False]),
    }
    for name, change in changes.items():
        document = json.loads(good)
        change(document)
        (folder / name).write_text(json.dumps(document))
    (folder / "nested.json").write_text("[" * 100_000 + "]" * 100_000)


def cases(folder: Path, log: str) -> dict[str, list[str]]:
    """What each hostile input is given to."""
    with gzip.open(log, "rt") as lines:
        first = next(line for line in lines if line.startswith("FLASER"))
    start = f"{first.split()[-3]},0,0,0"
    ros = ["ros2", "--loopback", "--duration", "0.1", "--ros-args"]
    out = ["--out", str(folder / "o.jsonl"), "--overwrite"]
    runs = {
        "414-byte alias bomb (--params-file)": [*ros, "--params-file", str(folder / "bomb.yaml")],
        "recursive alias (--params-file)": [*ros, "--params-file", str(folder / "recursive.yaml")],
        "100 KB of [ (-p)": [*ros, "-p", "min_points:=" + "[" * 100_000],
        "100 KB of [ (--params-file)": [*ros, "--params-file", str(folder / "deep.yaml")],
        "100 KB of [ (run --config)": ["run", log, "--config", str(folder / "deep.toml"), *out],
        "5,000 digits (-p)": [*ros, "-p", "min_points:=" + "1" * 5000],
        "-p sensor_profile:=/dev/zero": [*ros, "-p", "sensor_profile:=/dev/zero"],
        "run --sensor-profile /dev/zero": ["run", log, "--sensor-profile", "/dev/zero", *out],
        "profile noise 1e300": ["run", log, "--sensor-profile", str(folder / "noise.json"), *out],
        "hough rho_resolution=5e-324": [
            "run", log, "--method", "hough", "--param", "rho_resolution=5e-324", *out,
        ],
    }  # fmt: skip
    for name in ("far", "nan", "nested", "rho", "cov", "bool"):
        map_file = str(folder / f"{name}.json")
        runs[f"localize, map {name}.json"] = [
            "localize", log, "--map", map_file, "--initial-pose", start,
            "--out", str(folder / "p.tum"), "--overwrite",
        ]  # fmt: skip
    return runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--memory-gb", type=float, default=3.0)
    parser.add_argument("--timeout", type=float, default=60.0)
    args = parser.parse_args()
    limit = int(args.memory_gb * 2**30)

    def limited() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    log = str(sample("intel"))
    with tempfile.TemporaryDirectory(prefix="scanlines-hostile-") as scratch:
        folder = Path(scratch)
        write_files(folder, log)
        print("| input | exit | s | stderr chars | stderr lines | last line |")
        print("| --- | --- | --- | --- | --- | --- |")
        for name, words in cases(folder, log).items():
            started = time.perf_counter()
            try:
                done = subprocess.run(
                    [sys.executable, "-m", "scanlines", *words],
                    capture_output=True, text=True, timeout=args.timeout, preexec_fn=limited,
                    check=False,
                )  # fmt: skip
                code, err = str(done.returncode), done.stderr
            except subprocess.TimeoutExpired:
                code, err = "timeout", ""
            seconds = time.perf_counter() - started
            lines = err.strip().splitlines()
            last = (lines[-1] if lines else "").replace(scratch, "DIR").replace("|", "/")[:110]
            print(f"| {name} | {code} | {seconds:.1f} | {len(err)} | {len(lines)} | {last} |")


if __name__ == "__main__":
    main()
