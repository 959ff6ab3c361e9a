"""Fuzz the log readers and the map commands: mutate the seeds, run each input through
every channel of its target, report.

Usage, from the repository root::

    python -m tests.fuzz.run --count 5000 --seed 1 [--jobs 2] [--target all|logs|maps]
        [--save-failures DIR]

Targets: ``logs`` (every log format through the readers, ``info`` and ``run``) and
``maps`` (a CARMEN log's poses and a TUM file through ``map`` and ``eval --map``:
``map_target.py``); ``all`` (the default) both. Input ``i`` is seed ``i mod S`` (round
robin over the seeds of the targets) mutated by the next plan of that seed (round robin
over its mutators), with a generator seeded by ``(seed, i)``: the same ``--seed`` and
``--target`` always give the same inputs, and the first ``n`` inputs of a longer run are
those of a run of ``n``. Prints a table of outcomes by seed and channel and every defect;
exits 1 if there is any defect.
"""

from __future__ import annotations

import argparse
import random
import shutil
import sys
import tempfile
import threading
import time
from collections import Counter, defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from scanlines.data import sample

from .channels import (
    CHANNELS,
    CLEAN_ERROR,
    DEFAULT_MEMORY_LIMIT,
    DEFAULT_TIMEOUT,
    DEFECT,
    EXTRA_CHANNELS,
    SUCCESS,
    Outcome,
    Worker,
)
from .map_channels import MAP_CHANNELS
from .map_target import MAP_SEED_FILES, build_map_seeds, map_plans
from .plans import make_input, plans_for
from .seeds import SEED_FILES, build_seeds

#: Each target's seeds, its plans and its channels.
TARGETS = {
    "logs": (tuple(SEED_FILES), plans_for, CHANNELS),
    "maps": (tuple(MAP_SEED_FILES), map_plans, MAP_CHANNELS),
}
ALL_TARGETS = ("logs", "maps")


@dataclass
class Case:
    """One mutated input and what the channels made of it."""

    index: int
    seed_name: str
    plan: str
    path: Path
    outcomes: list[Outcome] = field(default_factory=list)
    saved: Path | None = None
    channels: tuple[str, ...] | None = None  # None: those of the run

    @property
    def defects(self) -> list[Outcome]:
        return [o for o in self.outcomes if o.kind == DEFECT]

    def saved_name(self, seed: int) -> str:
        """``format--mutator--seedS-index`` plus the seed's suffixes."""
        suffix = "".join(self.path.suffixes)
        return (
            f"{self.seed_name}--{self.plan.replace('/', '-')}--seed{seed}-{self.index:05d}{suffix}"
        )


def make_case(
    index: int,
    seed: int,
    seeds: dict[str, Path],
    folder: Path,
    targets: tuple[str, ...] = ("logs",),
) -> Case:
    names = [name for target in targets for name in TARGETS[target][0]]
    seed_name = names[index % len(names)]
    target = next(t for t in targets if seed_name in TARGETS[t][0])
    plans = TARGETS[target][1](seed_name)
    plan = plans[(index // len(names)) % len(plans)]
    rng = random.Random(f"{seed}:{index}")
    path = make_input(seeds[seed_name], plan, rng, folder / f"{index:05d}-{seeds[seed_name].name}")
    return Case(index, seed_name, plan.name, path, channels=TARGETS[target][2])


def remove(path: Path) -> None:
    if path.is_dir():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def save_input(case: Case, seed: int, folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / case.saved_name(seed)
    remove(target)
    if case.path.is_dir():
        shutil.copytree(case.path, target)
    else:
        shutil.copyfile(case.path, target)
    return target


def run_cases(
    make: Callable[[int], Case],
    count: int,
    *,
    workdir: Path,
    channels: tuple[str, ...] = CHANNELS,
    jobs: int = 1,
    save_failures: Path | None = None,
    seed: int = 0,
    remove_inputs: bool = False,
    timeout: float = DEFAULT_TIMEOUT,
    memory_limit: int = DEFAULT_MEMORY_LIMIT,
    progress: bool = False,
) -> list[Case]:
    """Cases ``make(0) ... make(count - 1)`` through ``channels``, in ``jobs`` workers."""
    cases: list[Case] = []
    pending = iter(range(count))
    lock = threading.Lock()
    failures: list[BaseException] = []

    def work(number: int) -> None:
        with Worker(
            workdir / f"worker-{number}",
            timeout=timeout,
            memory_limit=memory_limit,
            warm_up=sample("intel"),
        ) as worker:
            while not failures:
                with lock:
                    index = next(pending, None)
                if index is None:
                    return
                case = make(index)
                case.outcomes = worker.run_all(case.path, case.channels or channels)
                if case.defects and save_failures is not None:
                    case.saved = save_input(case, seed, save_failures)
                if remove_inputs:
                    remove(case.path)
                with lock:
                    cases.append(case)
                    if progress and len(cases) % 100 == 0:
                        print(f"  {len(cases)} of {count} inputs", file=sys.stderr)

    def guarded_work(number: int) -> None:
        try:
            work(number)
        except BaseException as exc:
            failures.append(exc)

    threads = [threading.Thread(target=guarded_work, args=(n,)) for n in range(jobs)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if failures:
        raise failures[0]
    return sorted(cases, key=lambda c: c.index)


def fuzz(
    count: int,
    seed: int = 1,
    *,
    workdir: Path | None = None,
    targets: tuple[str, ...] = ALL_TARGETS,
    **options: Any,
) -> list[Case]:
    """Generate ``count`` inputs of ``targets`` from ``seed`` and run each through every
    channel of its target.

    ``options`` are those of :func:`run_cases` (``jobs``, ``save_failures``, ...).
    """
    with tempfile.TemporaryDirectory(prefix="scanlines-fuzz-") as scratch:
        workdir = Path(scratch) if workdir is None else workdir
        seeds: dict[str, Path] = {}
        if "logs" in targets:
            seeds |= build_seeds(workdir / "seeds")
        if "maps" in targets:
            seeds |= build_map_seeds(workdir / "seeds")
        inputs = workdir / "inputs"
        shutil.rmtree(inputs, ignore_errors=True)
        inputs.mkdir(parents=True)

        def make(index: int) -> Case:
            return make_case(index, seed, seeds, inputs, targets)

        return run_cases(make, count, workdir=workdir, seed=seed, remove_inputs=True, **options)


def replay(paths: list[Path], *, workdir: Path | None = None, **options: Any) -> list[Case]:
    """Read saved inputs (files or bag directories) through every channel and ``run mcap``;
    map inputs (a folder with ``log.clf``) through the map channels."""
    with tempfile.TemporaryDirectory(prefix="scanlines-replay-") as scratch:
        workdir = Path(scratch) if workdir is None else workdir

        def make(index: int) -> Case:
            path = paths[index]
            channels = MAP_CHANNELS if is_map_input(path) else None
            return Case(index, path.name, "replay", path, channels=channels)

        options.setdefault("channels", CHANNELS + EXTRA_CHANNELS)
        return run_cases(make, len(paths), workdir=workdir, **options)


# -- reports -------------------------------------------------------------------------------


def outcome_table(cases: list[Case]) -> str:
    """Inputs by format and channel; each cell is success / clean error / defect."""
    counts: dict[tuple[str, str], Counter[str]] = defaultdict(Counter)
    inputs: Counter[str] = Counter()
    channels: dict[str, None] = {}
    for case in cases:
        inputs[case.seed_name] += 1
        for outcome in case.outcomes:
            channels[outcome.channel] = None
            counts[case.seed_name, outcome.channel][outcome.kind] += 1
            counts["total", outcome.channel][outcome.kind] += 1
    inputs["total"] = len(cases)
    names = list(inputs)
    widths = [max(len(n) for n in names), 6] + [max(14, len(c)) for c in channels]
    lines = ["cells: success / clean error / defect"]
    for cells in [["format", "inputs", *channels]] + [
        [name, str(inputs[name])]
        + [
            f"{c[SUCCESS]} / {c[CLEAN_ERROR]} / {c[DEFECT]}"
            for c in (counts[name, channel] for channel in channels)
        ]
        for name in names
    ]:
        lines.append("  ".join(v.ljust(w) for v, w in zip(cells, widths, strict=True)).rstrip())
    return "\n".join(lines)


def defect_lines(cases: list[Case]) -> list[str]:
    """One line per defect: format | mutator | channel | error | message | input."""
    return [
        f"{case.seed_name} | {case.plan} | {o.channel} | {o.error} | {o.message} | "
        f"{case.saved or case.path}"
        for case in cases
        for o in case.defects
    ]


def defect_kinds(cases: list[Case]) -> list[str]:
    """Defects grouped by format, channel and error, with a count and the first example."""
    groups: dict[tuple[str, str, str], list[tuple[Case, Outcome]]] = defaultdict(list)
    for case in cases:
        for o in case.defects:
            groups[case.seed_name, o.channel, o.error].append((case, o))
    lines = []
    for (name, channel, error), found in sorted(groups.items()):
        case, outcome = found[0]
        lines.append(
            f"{len(found):4d} x {name} | {channel} | {error} | e.g. {case.plan}: "
            f"{outcome.message} | {case.saved or case.path}"
        )
    return lines


def report(cases: list[Case], seconds: float | None = None, *, kinds: bool = True) -> str:
    """The outcome table, then every defect and (``kinds``) the defects grouped by kind."""
    parts = [outcome_table(cases)]
    if seconds is not None:
        parts.append(f"{len(cases)} inputs in {seconds:.0f} s")
    defects = defect_lines(cases)
    if defects:
        parts += [f"\ndefects ({len(defects)}): format | mutator | channel | error | message"]
        parts += defects
        if kinds:
            parts += ["\ndefect kinds: count x format | channel | error | example"]
            parts += defect_kinds(cases)
    else:
        parts.append("no defects")
    return "\n".join(parts)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.fuzz.run", description=__doc__)
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("--count", type=int, default=300, help="inputs to generate (300)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the mutations (1)")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (1)")
    parser.add_argument(
        "--target", choices=("all", *ALL_TARGETS), default="all", help="what to fuzz (all)"
    )
    parser.add_argument("--save-failures", type=Path, help="copy defective inputs here")
    parser.add_argument("--workdir", type=Path, help="keep seeds and outputs here (default: temp)")
    parser.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, help="s per channel (20)")
    parser.add_argument(
        "--memory-gb",
        type=float,
        default=DEFAULT_MEMORY_LIMIT / 2**30,
        help="address-space limit of a worker, GB (3)",
    )
    parser.add_argument(
        "--replay",
        type=Path,
        nargs="+",
        metavar="INPUT",
        help="instead of fuzzing, read these inputs (or the inputs in these "
        "folders, e.g. tests/fuzz/corpus) through every channel",
    )
    args = parser.parse_args(argv)
    options: dict[str, Any] = {
        "jobs": args.jobs,
        "workdir": args.workdir,
        "save_failures": args.save_failures,
        "timeout": args.timeout,
        "memory_limit": int(args.memory_gb * 2**30),
        "progress": True,
    }
    started = time.perf_counter()
    if args.replay:
        cases = replay(replay_inputs(args.replay), **options)
    else:
        targets = ALL_TARGETS if args.target == "all" else (args.target,)
        cases = fuzz(args.count, args.seed, targets=targets, **options)
    print(report(cases, time.perf_counter() - started))
    return 1 if any(case.defects for case in cases) else 0


def is_map_input(path: Path) -> bool:
    """A map target's input: a folder holding ``log.clf``."""
    return path.is_dir() and (path / "log.clf").is_file()


def replay_inputs(paths: list[Path]) -> list[Path]:
    """Files, bag directories and map inputs as given; another folder: its entries."""
    inputs = []
    for path in paths:
        if is_map_input(path):
            inputs.append(path)
        elif path.is_dir() and not (path / "metadata.yaml").exists() and path.suffix == "":
            inputs += sorted(p for p in path.iterdir() if p.suffix != ".md")
        else:
            inputs.append(path)
    return inputs


if __name__ == "__main__":
    sys.exit(main())
