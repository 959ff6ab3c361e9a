"""Which mutators are tried on which seed, and writing one mutated input.

A :class:`Plan` names a mutator and, for a ROS 2 bag directory, the file it
damages. Plain text seeds get the byte and line mutators; gzip text seeds the
byte mutators on the compressed bytes (``gz-bytes/...``) and every text mutator
on the content (``text/...``); the NPZ seed the byte and NPZ mutators; bag
directories the byte mutators on the storage file (``storage/...``; a ``.db3``
also NULL fields, ``mutate_bags.py``) and the text mutators on ``metadata.yaml``
(``metadata/...``); the ROS 1 bag the byte mutators and the bag-structure ones (chunk
counts, index position, truncation inside the chunks); other binary seeds the byte
mutators.
"""

from __future__ import annotations

import random
import shutil
from dataclasses import dataclass
from pathlib import Path

from .mutate import BYTE_MUTATORS, LINE_MUTATORS, Mutator, inside_gzip
from .mutate_bags import DB3_MUTATORS, ROS1_MUTATORS
from .mutate_npz import NPZ_MUTATORS

PLAIN_TEXT_SEEDS = ("carmen-log", "carmen-robotlaser", "coreslam-dat", "csv")
GZIP_TEXT_SEEDS = ("carmen-clf-gz", "coreslam-dat-gz", "csv-gz")
BAG_DIRECTORY_SEEDS = ("ros2-db3-dir", "ros2-mcap-dir")


@dataclass(frozen=True)
class Plan:
    """One way of mutating a seed: ``name`` (e.g. ``text/bad_number``), the mutator and,
    for a folder (a bag directory, a map input), the file it damages (``"storage"``: the
    bag's storage file; else the file's name, e.g. ``"metadata.yaml"``, ``"poses.tum"``)."""

    name: str
    mutator: Mutator
    target: str | None = None


def interleave(*families: list[Plan]) -> list[Plan]:
    """Alternate the families, so that a short run tries some plans of each."""
    plans: list[Plan] = []
    for k in range(max(len(f) for f in families)):
        plans += [f[k] for f in families if k < len(f)]
    return plans


def plans_for(seed_name: str) -> list[Plan]:
    """Every plan tried on the seed ``seed_name`` (a key of ``seeds.SEED_FILES``)."""
    text_mutators = LINE_MUTATORS | BYTE_MUTATORS
    if seed_name in PLAIN_TEXT_SEEDS:
        return [Plan(name, m) for name, m in text_mutators.items()]
    if seed_name in GZIP_TEXT_SEEDS:
        return interleave(
            [Plan(f"text/{name}", inside_gzip(m)) for name, m in text_mutators.items()],
            [Plan(f"gz-bytes/{name}", m) for name, m in BYTE_MUTATORS.items()],
        )
    if seed_name == "npz":
        return interleave(
            [Plan(name, m) for name, m in NPZ_MUTATORS.items()],
            [Plan(name, m) for name, m in BYTE_MUTATORS.items()],
        )
    if seed_name == "ros1-bag":
        return interleave(
            [Plan(name, m) for name, m in BYTE_MUTATORS.items()],
            [Plan(name, m) for name, m in ROS1_MUTATORS.items()],
        )
    if seed_name in BAG_DIRECTORY_SEEDS:
        storage = BYTE_MUTATORS | (DB3_MUTATORS if seed_name == "ros2-db3-dir" else {})
        return interleave(
            [Plan(f"storage/{name}", m, "storage") for name, m in storage.items()],
            [Plan(f"metadata/{name}", m, "metadata.yaml") for name, m in text_mutators.items()],
        )
    return [Plan(name, m) for name, m in BYTE_MUTATORS.items()]


def make_input(seed: Path, plan: Plan, rng: random.Random, destination: Path) -> Path:
    """Write the seed, mutated by ``plan``, at ``destination`` (a file, or a bag directory)."""
    if not seed.is_dir():
        destination.write_bytes(plan.mutator(rng, seed.read_bytes()))
        return destination
    shutil.copytree(seed, destination)
    if plan.target not in (None, "storage"):  # a file of the folder by name
        target = destination / plan.target
    else:
        target = next(p for p in sorted(destination.iterdir()) if p.name != "metadata.yaml")
    target.write_bytes(plan.mutator(rng, target.read_bytes()))
    return destination
