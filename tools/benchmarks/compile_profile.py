"""Where one method's cold compile goes: seconds per compiled function, its callees excluded.

    NUMBA_CACHE_DIR=$(mktemp -d) taskset -c 0 python tools/benchmarks/compile_profile.py adaptive

Prints the total, the functions by exclusive seconds (numba's own numpy implementations
as ``numba.*``), and the sums by size class. Run it with an empty cache, else it times
cache loads.
"""

from __future__ import annotations

import argparse
import collections
import time

import numba.core.event

from scanlines import Extractor


class ExclusiveClock(numba.core.event.Listener):
    """Seconds of each compiled function, the compiles it starts inside it excluded."""

    def __init__(self) -> None:
        self.running: list[list] = []
        self.seconds: collections.Counter[str] = collections.Counter()
        self.compiles: collections.Counter[str] = collections.Counter()

    def on_start(self, event) -> None:
        now = time.perf_counter()
        if self.running:
            outer, since = self.running[-1]
            self.seconds[outer] += now - since
        function = event.data["dispatcher"].py_func
        name = f"{function.__module__.removeprefix('scanlines.')}.{function.__name__}"
        self.running.append([name, now])
        self.compiles[name] += 1

    def on_end(self, event) -> None:
        now = time.perf_counter()
        name, since = self.running.pop()
        self.seconds[name] += now - since
        if self.running:
            self.running[-1][1] = now


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("method")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args()
    clock = ExclusiveClock()
    numba.core.event.register("numba:compile", clock)
    start = time.perf_counter()
    Extractor(args.method).warm_up()
    total = time.perf_counter() - start
    print(f"{args.method}: {total:.1f} s, {len(clock.seconds)} functions, "
          f"{sum(clock.compiles.values())} compiles")  # fmt: skip
    for name, seconds in clock.seconds.most_common(args.top):
        print(f"{seconds:6.2f} s  x{clock.compiles[name]}  {name}")
    own = {n: s for n, s in clock.seconds.items() if not n.startswith("numba.")}
    library = total_of(clock.seconds, lambda n: n.startswith("numba."))
    print(f"package kernels: {len(own)}, {sum(own.values()):.1f} s; numba's numpy: {library:.1f} s")
    for bound in (0.1, 0.2, 0.3):
        small = [s for s in own.values() if s < bound]
        print(f"kernels under {bound} s: {len(small)}, {sum(small):.1f} s together")


def total_of(seconds: collections.Counter[str], chosen) -> float:
    return sum(s for name, s in seconds.items() if chosen(name))


if __name__ == "__main__":
    main()
