"""The viewer's two targets, measured in real headless Chromium driven by Playwright.

    python tools/benchmarks/viewer.py [--changes 20] [--scans 50000] [--work /tmp/viewer-bench]

1. A parameter change on a 1,000-beam scan, for every method (kernels warm): the time
   from the input event to the redrawn frame, as the page measures it (the event's
   timestamp to the animation frame after drawing), median of ``--changes`` changes of
   ``min_points``; beside it the same change timed from Playwright (fill() to the frame
   counter moving, which adds the driver's round trips). Target: under 250 ms.
2. Opening a ``--scans``-scan log (the shipped Intel excerpt repeated, CARMEN): from
   starting ``scanlines view LOG --no-browser`` to the first drawn scan in the page (its
   returns, drawn before the extractor is ready) and to its features, and
   the process's resident memory 25 s after the start (the whole log read, every
   method's kernels loaded), beside that of the 300-scan excerpt. Target: under 2 s.

The browser is ``$SCANLINES_CHROMIUM``, else ``chromium`` on the PATH.
"""

from __future__ import annotations

import argparse
import dataclasses
import gzip
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np

#: The page has drawn the first scan's features (its returns come first, alone).
FEATURES_DRAWN = (
    "window.viewer && window.viewer.state.frame && window.viewer.state.frame.results.length > 0"
    " && window.viewer.stats.frames > 1"
)
#: Seconds after the start at which the resident memory is read.
SETTLED = 25.0
FLAGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]  # fmt: skip


def thousand_beam_log(folder: Path, scans: int = 20) -> Path:
    """Simulated scans of a 1,000-beam sensor (270 degrees) in random rooms, as .npz."""
    from scanlines.sim import get_sensor, random_scene

    base = get_sensor("tim571")
    sensor = dataclasses.replace(
        base, name="bench_1000", n_beams=1000, angle_min=-0.75 * np.pi,
        angle_increment=1.5 * np.pi / 999,
    )  # fmt: skip
    ranges = [random_scene(seed=k, sensor=sensor).scan(seed=k).scan.ranges for k in range(scans)]
    path = folder / "thousand_beams.npz"
    np.savez(path, ranges=np.array(ranges), angle_min=sensor.angle_min,
             angle_increment=sensor.angle_increment, range_max=sensor.range_max)  # fmt: skip
    return path


def long_log(folder: Path, scans: int) -> Path:
    from scanlines.data import sample

    lines = gzip.decompress(sample("intel").read_bytes()).splitlines(keepends=True)
    path = folder / f"intel_{scans}.clf"
    with path.open("wb") as log:
        for k in range(scans):
            log.write(lines[k % len(lines)])
    return path


def start_view(log: Path) -> tuple[subprocess.Popen, str, float]:
    started = time.perf_counter()
    process = subprocess.Popen(
        [sys.executable, "-m", "scanlines", "view", str(log), "--no-browser"],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    line = process.stdout.readline()
    match = re.search(r"(http://\S+/)", line)
    if not match:
        process.kill()
        raise SystemExit(f"scanlines view did not start: {line!r}")
    return process, match.group(1), started


def resident_mb(process: subprocess.Popen) -> float:
    status = Path(f"/proc/{process.pid}/status").read_text()
    return int(re.search(r"VmRSS:\s+(\d+)", status).group(1)) / 1024


def wait_until_read(url: str) -> None:
    while True:
        with urllib.request.urlopen(url + "api/log") as response:
            if json.loads(response.read())["finished"]:
                return
        time.sleep(0.2)


def frames(page) -> int:
    return page.evaluate("window.viewer.stats.frames")


def redrawn(page, before: int) -> None:
    page.wait_for_function(f"window.viewer.stats.frames > {before}", timeout=120_000)


def change_latencies(browser, log: Path, changes: int) -> None:
    from scanlines import method_names

    process, url, _ = start_view(log)
    try:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(url)
        page.wait_for_function(FEATURES_DRAWN)
        field = page.locator('#config-0 input[aria-label="min_points"]')
        print(f"parameter change on a {page.evaluate('window.viewer.state.frame.beams')}-beam "
              f"scan, median of {changes} (ms): in the page / from Playwright")  # fmt: skip
        for method in method_names():
            before = frames(page)
            page.locator("#config-0 .method").select_option(method)
            redrawn(page, before)
            for value in (7, 8, 7):  # kernels warm, compiled if the background had not yet
                before = frames(page)
                field.fill(str(value))
                redrawn(page, before)
            page.evaluate("window.viewer.stats.latencies = []")
            outside = []
            for k in range(changes):
                before = frames(page)
                started = time.perf_counter()
                field.fill(str(6 + k % 2))
                redrawn(page, before)
                outside.append(1000 * (time.perf_counter() - started))
            inside = page.evaluate("window.viewer.stats.latencies")
            segments = page.evaluate("window.viewer.stats.drawn.segments[0]")
            page_ms, driver_ms = statistics.median(inside), statistics.median(outside)
            print(f"  {method:<16} {page_ms:7.1f} {driver_ms:7.1f}"
                  f"   (max {max(inside):.1f}; {segments} segments)")  # fmt: skip
        page.close()
    finally:
        process.terminate()
        process.wait()


def opening_time(browser, log: Path, scans: int) -> None:
    process, url, started = start_view(log)
    try:
        printed = time.perf_counter() - started
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(url)
        page.wait_for_function("window.viewer && window.viewer.stats.frames > 0", timeout=120_000)
        drawn = time.perf_counter() - started
        page.wait_for_function(FEATURES_DRAWN, timeout=120_000)
        extracted = time.perf_counter() - started
        wait_until_read(url)
        read = time.perf_counter() - started
        time.sleep(max(0.0, SETTLED - read))  # every method's kernels loaded by then
        print(f"opening a {scans:,}-scan log: address printed {printed:.2f} s, first scan drawn "
              f"{drawn:.2f} s, its features {extracted:.2f} s, whole log read {read:.1f} s, "
              f"resident memory at {SETTLED:.0f} s {resident_mb(process):.0f} MB")  # fmt: skip
        page.close()
    finally:
        process.terminate()
        process.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--changes", type=int, default=20)
    parser.add_argument("--scans", type=int, default=50_000)
    parser.add_argument("--work", type=Path, default=Path("/tmp/viewer-bench"))
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    executable = os.environ.get("SCANLINES_CHROMIUM") or shutil.which("chromium")
    if executable is None:
        raise SystemExit("no Chromium: install Debian's chromium or set SCANLINES_CHROMIUM")
    from playwright.sync_api import sync_playwright

    from scanlines.data import sample

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=FLAGS)
        change_latencies(browser, thousand_beam_log(args.work), args.changes)
        opening_time(browser, sample("intel"), 300)
        opening_time(browser, long_log(args.work, args.scans), args.scans)
        browser.close()


if __name__ == "__main__":
    main()
