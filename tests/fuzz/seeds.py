"""Small valid logs of every readable format, the starting points of the mutations.

:func:`build_seeds` writes them into a folder and returns ``{seed name: path}``.
Each holds 12 to 25 scans. The text logs are excerpts of the shipped samples;
the tables, stacks and bags carry scans of the Intel sample.
"""

from __future__ import annotations

import gzip
import itertools
import shutil
import sys
from pathlib import Path

import numpy as np

from scanlines.data import sample
from scanlines.io import open_log
from scanlines.scan import Scan

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "io"))
from bag_helpers import write_bag

SEED_SCANS = 20

#: Seed name -> file (or bag directory) name.
SEED_FILES = {
    "carmen-log": "freiburg.log",
    "carmen-clf-gz": "intel.clf.gz",
    "carmen-robotlaser": "robotlaser.log",
    "coreslam-dat": "urg.dat",
    "coreslam-dat-gz": "urg.dat.gz",
    "csv": "table.csv",
    "csv-gz": "table.csv.gz",
    "npz": "stack.npz",
    "ros1-bag": "scans.bag",
    "ros2-db3-dir": "scans_db3",
    "ros2-mcap-file": "scans.mcap",
    "ros2-mcap-dir": "scans_mcap",
    "results-mcap": "results.mcap",
}


def sample_lines(name: str) -> list[str]:
    with gzip.open(sample(name), "rt", encoding="utf-8") as fh:
        return fh.read().splitlines()


def carmen_excerpt(name: str, laser_records: int, keep_params: tuple[str, ...] = ()) -> str:
    """Comments, the chosen ``PARAM`` lines, then the lines up to ``laser_records`` ``FLASER``."""
    kept, lasers = [], 0
    for line in sample_lines(name):
        keyword = line.split(" ", 1)[0]
        if keyword == "PARAM" and line.split()[1] not in keep_params:
            continue
        if lasers == laser_records and keyword not in ("#", "PARAM"):
            break
        lasers += keyword == "FLASER"
        kept.append(line)
    return "\n".join(kept) + "\n"


def intel_scans(count: int = SEED_SCANS) -> list[Scan]:
    return list(itertools.islice(open_log(sample("intel")), count))


def robotlaser_log(scans: list[Scan]) -> str:
    """The scans as ``ROBOTLASER1`` lines with 180 remissions, after an ``ODOM`` line each."""
    lines = ["# CARMEN Logfile written for the fuzzing seeds"]
    for scan in scans:
        x, y, theta = scan.pose or (0.0, 0.0, 0.0)
        stamp = f"{scan.timestamp:.6f} seedhost {scan.timestamp:.6f}"
        ranges = " ".join(f"{r:.3f}" for r in np.nan_to_num(scan.ranges, nan=81.83))
        remissions = " ".join(str(k % 7) for k in range(len(scan)))
        lines.append(f"ODOM {x:.3f} {y:.3f} {theta:.6f} 0.1 0.0 0.0 {stamp}")
        lines.append(
            f"ROBOTLASER1 0 {scan.angle_min:.6f} {np.pi:.6f} {scan.angle_increment:.6f} 81.8 "
            f"0.01 0 {len(scan)} {ranges} {len(scan)} {remissions} {x:.3f} {y:.3f} "
            f"{theta:.6f} {x:.3f} {y:.3f} {theta:.6f} 0.1 0.0 0.5 0.2 0.0 {stamp}"
        )
    return "\n".join(lines) + "\n"


def coreslam_excerpt(count: int = 15) -> str:
    return "\n".join(sample_lines("urg")[:count]) + "\n"


def table_csv(scans: list[Scan]) -> str:
    """A preamble with the geometry, a ``timestamp,r0,r1,...`` header, one row per scan."""
    first = scans[0]
    lines = [
        f"# angle_min={first.angle_min!r} angle_increment={first.angle_increment!r}",
        f"# range_max={first.range_max!r}",
        ",".join(["timestamp", *(f"r{k}" for k in range(len(first)))]),
    ]
    for scan in scans:
        values = ["" if np.isnan(r) else f"{r:.3f}" for r in scan.ranges]
        lines.append(",".join([f"{scan.timestamp:.6f}", *values]))
    return "\n".join(lines) + "\n"


def write_npz(path: Path, scans: list[Scan]) -> None:
    np.savez(
        path,
        ranges=np.array([s.ranges for s in scans], dtype=np.float32),
        angle_min=scans[0].angle_min,
        angle_increment=scans[0].angle_increment,
        range_max=np.full(len(scans), scans[0].range_max),
        timestamps=np.array([s.timestamp for s in scans]),
        poses=np.array([s.pose for s in scans]),
    )


def write_results_mcap(path: Path, scans: list[Scan]) -> None:
    """Extraction results as scanlines itself writes them (its ``.mcap`` holds the scans)."""
    from scanlines import extract
    from scanlines.io import open_writer

    with open_writer(path) as writer:
        for index, scan in enumerate(scans):
            writer.write(index, scan, extract(scan))


def write_gzip(path: Path, text: str) -> None:
    path.write_bytes(gzip.compress(text.encode(), mtime=0))


def build_seeds(folder: Path) -> dict[str, Path]:
    """Write every seed into ``folder`` (created) and return ``{seed name: path}``."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = {name: folder / file for name, file in SEED_FILES.items()}
    scans = intel_scans()
    freiburg_params = ("robot_front_laser_max", "laser_front_laser_fov", "robot_frontlaser_offset")
    paths["carmen-log"].write_text(carmen_excerpt("freiburg", 12, freiburg_params))
    write_gzip(paths["carmen-clf-gz"], carmen_excerpt("intel", SEED_SCANS))
    paths["carmen-robotlaser"].write_text(robotlaser_log(scans[:12]))
    paths["coreslam-dat"].write_text(coreslam_excerpt())
    write_gzip(paths["coreslam-dat-gz"], coreslam_excerpt())
    paths["csv"].write_text(table_csv(scans))
    write_gzip(paths["csv-gz"], table_csv(scans))
    write_npz(paths["npz"], scans)
    for name in ("ros1-bag", "ros2-db3-dir", "ros2-mcap-dir", "results-mcap"):
        shutil.rmtree(paths[name], ignore_errors=True)  # the bag writers refuse to overwrite
        paths[name].unlink(missing_ok=True)
    write_bag(paths["ros1-bag"], "ros1", scans)
    write_bag(paths["ros2-db3-dir"], "sqlite3", scans)
    write_bag(paths["ros2-mcap-dir"], "mcap", scans)
    storage = next(paths["ros2-mcap-dir"].glob("*.mcap"))
    paths["ros2-mcap-file"].write_bytes(storage.read_bytes())
    write_results_mcap(paths["results-mcap"], scans[:12])
    return paths
