"""Fuzz the log readers, the map commands, the files that set things and the ROS 2 node:
mutate the seeds, try each input, report.

Usage, from the repository root::

    python -m tests.fuzz.run --count 5000 --seed 1 [--jobs 2]
        [--targets logs maps params profiles linemaps dds] [--save-failures DIR]

Six targets. ``logs``: every log format (``seeds.py``), mutated by the plans of
``plans.py``, read through every channel of ``channels.py`` (the library, ``info``,
``run``). ``maps``: a CARMEN log's poses and a TUM file of them (``map_target.py``),
mutated by ``mutate_maps.py``, through ``map`` and ``eval --map`` (``map_channels.py``).
``params``, ``profiles``, ``linemaps``: a parameters file and a configuration, a sensor
profile, the line map ``localize`` reads (``file_target.py``), mutated by
``mutate_files.py``, read and run through ``file_channels.py``.
``dds``: a LaserScan sample mutated by ``mutate_cdr.py``, sent to one running ROS 2 node
(``dds_target.py``); it starts a node, so it runs only when named. ``--targets`` takes
any of them (default: all but ``dds``). ``--count`` is shared: input ``k`` of the campaign
goes to target ``k mod T`` of the ``T`` named. Input ``i`` of a seeded target is
seed ``i mod S`` of that target (round robin over its seeds) mutated by the next plan of
that seed (round robin over its mutators); input ``i`` of ``dds`` is the sample mutated by
plan ``i mod P``. Each target's generator is seeded by ``(seed, i)``: the same ``--seed``
always gives the same inputs, and the first ``n`` inputs of a target in a longer run are
those of a run of ``n``. Prints a table of outcomes by seed and channel for each target
and every defect; exits 1 if there is any defect. ``--replay`` takes saved inputs: log
files and bag directories, map inputs (a folder with ``log.clf``), settings inputs (a
folder with ``log.clf`` and ``params.yaml``, ``config.toml``, ``profile.json`` or
``map.json``) and DDS samples (``.cdr``, sent to a node). A shared object rewritten during
the campaign (``binaries.py``: another build of the core copied over the installed one)
ends it with one line, exit 2: the crashes it causes are not the inputs'.
"""

from __future__ import annotations

import argparse
import gc
import os
import random
import shutil
import sys
import tempfile
import threading
import time
from collections import Counter, defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

from scanlines.data import sample

from .binaries import BinaryChanged, BinaryWatch
from .channels import (
    CHANNELS,
    CLEAN_ERROR,
    DEFAULT_MEMORY_LIMIT,
    DEFAULT_TIMEOUT,
    DEFECT,
    EXTRA_CHANNELS,
    SUCCESS,
    Case,
    Outcome,
    Worker,
)
from .file_channels import FILE_CHANNELS
from .file_target import build_file_seeds, file_input_kind, file_plans, seeds_of
from .map_channels import MAP_CHANNELS
from .map_target import MAP_SEED_FILES, build_map_seeds, map_plans
from .plans import Plan, make_input, plans_for
from .seeds import SEED_FILES, build_seeds


class SeededTarget(NamedTuple):
    """A target whose inputs are mutated seed files: its seeds (names), how they are
    written, the plans of a seed and the channels its inputs go through."""

    seeds: tuple[str, ...]
    build: Callable[[Path], dict[str, Path]]
    plans: Callable[[str], list[Plan]]
    channels: tuple[str, ...]


#: The targets made of mutated seed files, in worker processes (``channels.py``).
SEEDED_TARGETS = {
    "logs": SeededTarget(tuple(SEED_FILES), build_seeds, plans_for, CHANNELS),
    "maps": SeededTarget(tuple(MAP_SEED_FILES), build_map_seeds, map_plans, MAP_CHANNELS),
    **{
        target: SeededTarget(
            seeds_of(target),
            lambda folder, target=target: build_file_seeds(folder, target),
            file_plans,
            channels,
        )
        for target, channels in FILE_CHANNELS.items()
    },
}
#: What inputs go to: the log readers, the map commands, the files that set things
#: (parameters files and configurations, sensor profiles, line maps), a ROS 2 node
#: (``dds_target.py``).
TARGETS = ("logs", "maps", "params", "profiles", "linemaps", "dds")
#: Those of a run that names none (``dds`` starts a node: only when named).
DEFAULT_TARGETS = ("logs", "maps", "params", "profiles", "linemaps")


def make_case(
    index: int, seed: int, seeds: dict[str, Path], folder: Path, target: str = "logs"
) -> Case:
    """Input ``index`` of ``target``: its seed ``index mod S`` mutated by that seed's next
    plan, with a generator seeded by ``seed:index`` (a run of one target makes the inputs
    that target made before the targets shared a campaign)."""
    spec = SEEDED_TARGETS[target]
    seed_name = spec.seeds[index % len(spec.seeds)]
    plans = spec.plans(seed_name)
    plan = plans[(index // len(spec.seeds)) % len(plans)]
    rng = random.Random(f"{seed}:{index}")
    path = make_input(seeds[seed_name], plan, rng, folder / f"{index:05d}-{seeds[seed_name].name}")
    return Case(index, seed_name, plan.name, path, channels=spec.channels)


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
    watch: BinaryWatch | None = None,
) -> list[Case]:
    """Cases ``make(0) ... make(count - 1)``, each through its own channels (``channels``
    where it has none), in ``jobs`` workers; ``watch`` checked by each worker and at the
    end."""
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
            watch=watch,
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
    if watch is not None:
        watch.check("after the inputs")
    return sorted(cases, key=lambda c: c.index)


def without_domain(options: dict[str, Any]) -> dict[str, Any]:
    """``options`` less the DDS target's own (``domain``), for :func:`run_cases`."""
    return {k: v for k, v in options.items() if k != "domain"}


def fuzz(
    count: int,
    seed: int = 1,
    *,
    targets: tuple[str, ...] = DEFAULT_TARGETS,
    workdir: Path | None = None,
    **options: Any,
) -> list[Case]:
    """Generate ``count`` inputs from ``seed``, shared round robin between ``targets``
    (``logs``: read through every channel; ``maps``: through ``map`` and ``eval --map``;
    ``dds``: sent to a ROS 2 node, on ``options["domain"]``).

    ``options`` are those of :func:`run_cases` (``jobs``, ``save_failures``, ...).

    Every target's seeds are written first, and what they left collected: past that point
    this process runs no code of the compiled core (the workers and the node do), so a core
    rewritten under the campaign is found by the :class:`BinaryWatch` (``options["watch"]``,
    by default one made then) rather than crashing this process first (``binaries.py``).
    """
    targets = tuple(dict.fromkeys(targets))
    unknown = set(targets) - set(TARGETS)
    if unknown or not targets:
        raise ValueError(f"targets are {', '.join(TARGETS)}, got {', '.join(targets)}")
    counts = {target: len(range(k, count, len(targets))) for k, target in enumerate(targets)}
    with tempfile.TemporaryDirectory(prefix="scanlines-fuzz-") as scratch:
        workdir = Path(scratch) if workdir is None else workdir
        seeds = {
            target: SEEDED_TARGETS[target].build(workdir / "seeds")
            for target, n in counts.items()
            if n and target in SEEDED_TARGETS
        }
        sample = dds_seed() if counts.get("dds") else b""
        gc.collect()  # arrays the core allocated are freed while it is intact
        if "watch" not in options:
            options["watch"] = BinaryWatch()
        cases = []
        for target, n in counts.items():
            if n and target == "dds":
                cases += fuzz_dds(n, seed, workdir, sample, **options)
            elif n:
                cases += fuzz_seeded(
                    target, n, seed, workdir, seeds[target], **without_domain(options)
                )
        return cases


def fuzz_seeded(
    target: str, count: int, seed: int, workdir: Path, seeds: dict[str, Path], **options: Any
) -> list[Case]:
    """``count`` inputs of a seeded target (``logs``, ``maps``; its ``seeds`` written)
    through its channels."""
    inputs = workdir / f"{target}-inputs"
    shutil.rmtree(inputs, ignore_errors=True)
    inputs.mkdir(parents=True)

    def make(index: int) -> Case:
        return make_case(index, seed, seeds, inputs, target)

    return run_cases(make, count, workdir=workdir, seed=seed, remove_inputs=True, **options)


def dds_seed() -> bytes:
    """The LaserScan sample the DDS target mutates (``mutate_cdr.seed_sample``)."""
    from .mutate_cdr import seed_sample

    return seed_sample()


def fuzz_dds(count: int, seed: int, workdir: Path, sample: bytes, **options: Any) -> list[Case]:
    """``count`` mutations of the LaserScan ``sample`` sent to one ROS 2 node
    (``dds_target``)."""
    from .mutate_cdr import plans

    mutators = plans()

    def make(index: int) -> tuple[str, bytes]:
        name, mutator = mutators[index % len(mutators)]
        return name, mutator(random.Random(f"dds:{seed}:{index}"), sample)

    return _dds_cases(make, count, workdir, sample, seed, **options)


def _dds_cases(make, count, workdir, sample, seed=0, **options: Any) -> list[Case]:
    """:func:`dds_target.run_dds` (on ``options["domain"]``, default 97); defective inputs
    saved (``save_failures``), the others removed."""
    from .dds_target import DEFAULT_DOMAIN, run_dds

    domain = options.get("domain", DEFAULT_DOMAIN)
    if domain is None:  # a domain no other process on this machine uses
        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
        from dds_domains import free_domain

        domain = free_domain()
    progress, watch = options.get("progress", False), options.get("watch")
    cases = run_dds(
        make, count, workdir=workdir, seed=sample, domain=domain, progress=progress, watch=watch
    )
    for case in cases:
        if case.defects and options.get("save_failures") is not None:
            case.saved = save_input(case, seed, options["save_failures"])
        remove(case.path)
    return cases


def replay(paths: list[Path], *, workdir: Path | None = None, **options: Any) -> list[Case]:
    """Read saved inputs (files or bag directories) through every channel and ``run mcap``,
    map inputs (a folder with ``log.clf``) through the map channels; send saved DDS samples
    (``.cdr``) to a ROS 2 node."""
    samples = [p for p in paths if p.suffix == ".cdr"]
    paths = [p for p in paths if p.suffix != ".cdr"]
    options.setdefault("watch", BinaryWatch())
    with tempfile.TemporaryDirectory(prefix="scanlines-replay-") as scratch:
        workdir = Path(scratch) if workdir is None else workdir
        cases = []
        if paths:

            def make(index: int) -> Case:
                path = paths[index]
                kind = file_input_kind(path)
                channels = FILE_CHANNELS[kind] if kind else None
                channels = MAP_CHANNELS if channels is None and is_map_input(path) else channels
                return Case(index, path.name, "replay", path, channels=channels)

            logs_options = without_domain(options)
            logs_options.setdefault("channels", CHANNELS + EXTRA_CHANNELS)
            cases += run_cases(make, len(paths), workdir=workdir, **logs_options)
        if samples:
            from .mutate_cdr import seed_sample

            def make_sample(index: int) -> tuple[str, bytes]:
                return f"replay {samples[index].name}", samples[index].read_bytes()

            options.pop("save_failures", None)  # they are saved already
            cases += _dds_cases(make_sample, len(samples), workdir, seed_sample(), **options)
        return cases


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
    """The outcome tables (the logs', the maps', the DDS node's by mutator), then every
    defect and (``kinds``) the defects grouped by kind."""
    from .dds_target import SEED_NAME, outcomes_by_plan

    samples = [case for case in cases if case.seed_name == SEED_NAME]
    groups = {channels: [] for channels in (MAP_CHANNELS, *FILE_CHANNELS.values())}
    logs = []
    for case in cases:
        if case.seed_name != SEED_NAME:
            groups.get(case.channels, logs).append(case)
    parts = [outcome_table(group) for group in (logs, *groups.values()) if group]
    parts += [outcomes_by_plan(samples)] if samples else []
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
        help="instead of fuzzing, read these inputs (or the inputs in these folders, e.g. "
        "tests/fuzz/corpus) through every channel of their target: log files and bags, "
        "map inputs (a folder with log.clf), DDS samples (.cdr)",
    )
    parser.add_argument(
        "--targets",
        nargs="+",
        action="extend",
        choices=TARGETS,
        metavar="TARGET",
        help="what the inputs go to, any of logs (the log readers), maps (the map "
        "commands), params (parameters files and configurations), profiles (sensor "
        "profiles), linemaps (the line maps localize reads), dds (a ROS 2 node: started "
        "only when named); space separated or repeated (logs maps params profiles linemaps)",
    )
    parser.add_argument(
        "--domain-id",
        type=int,
        default=None,
        help="dds: the DDS domain (default: one no other process on this machine uses)",
    )
    args = parser.parse_args(argv)
    options: dict[str, Any] = {
        "jobs": args.jobs,
        "workdir": args.workdir,
        "save_failures": args.save_failures,
        "timeout": args.timeout,
        "memory_limit": int(args.memory_gb * 2**30),
        "progress": True,
        "domain": args.domain_id,
    }
    started = time.perf_counter()
    try:
        if args.replay:
            cases = replay(replay_inputs(args.replay), **options)
        else:
            targets = tuple(args.targets or DEFAULT_TARGETS)
            cases = fuzz(args.count, args.seed, targets=targets, **options)
    except BinaryChanged as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return BINARY_CHANGED
    print(report(cases, time.perf_counter() - started))
    return 1 if any(case.defects for case in cases) else 0


def is_map_input(path: Path) -> bool:
    """A map target's input (a folder holding ``log.clf``), or a settings file's (a folder
    holding ``log.clf`` and the file: ``file_target.py``)."""
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


#: The exit status of a campaign ended by a shared object rewritten under it.
BINARY_CHANGED = 2

if __name__ == "__main__":
    status = main()
    if status == BINARY_CHANGED:  # this process's copy of the core may be damaged too:
        sys.stdout.flush()  # its clean-up at exit would run it, so there is none
        sys.stderr.flush()
        os._exit(status)
    sys.exit(status)
