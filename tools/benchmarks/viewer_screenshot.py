"""The README's screenshot of the viewer: the Freiburg 079 excerpt, the default adaptive
method against the same with ``min_points`` 10, overlaid, with a segment selected.

    python tools/benchmarks/viewer_screenshot.py [--out docs/figures/viewer.png] [--scan 120]
"""

from __future__ import annotations

import argparse
import os
import shutil
from pathlib import Path

from viewer import FEATURES_DRAWN, FLAGS, frames, redrawn

from scanlines.data import sample
from scanlines.viewer import ScanStore, ViewerServer, ViewerSession

CENTROID = """(() => {
  const f = window.viewer.state.frame, keep = f.x.map((x, i) => x !== null && f.y[i] !== null);
  const count = keep.filter(Boolean).length;
  const mean = (v) => v.filter((_, i) => keep[i]).reduce((a, b) => a + b, 0) / count;
  return [mean(f.x), mean(f.y)];
})()"""


def on_screen(page, x: float, y: float) -> tuple[float, float]:
    """Page coordinates of the point ``(x, y)`` metres of the first view."""
    transform = page.evaluate("window.viewer.state.transform")
    box = page.locator("#view-0 canvas").bounding_box()
    return (box["x"] + transform["x"] + x * transform["scale"],
            box["y"] + transform["y"] - y * transform["scale"])  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/figures/viewer.png"))
    parser.add_argument("--scan", type=int, default=120)
    args = parser.parse_args()
    executable = os.environ.get("SCANLINES_CHROMIUM") or shutil.which("chromium")
    from playwright.sync_api import sync_playwright

    server = ViewerServer(ViewerSession(ScanStore(sample("freiburg")))).start()
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=executable, args=FLAGS)
            page = browser.new_page(viewport={"width": 1500, "height": 860})
            page.goto(server.url)
            page.wait_for_function(FEATURES_DRAWN)
            before = frames(page)
            page.locator("#scan-index").fill(str(args.scan))
            page.locator("#scan-index").dispatch_event("change")
            redrawn(page, before)
            before = frames(page)
            page.locator("#compare").check()
            redrawn(page, before)
            before = frames(page)
            page.locator('#config-1 input[aria-label="min_points"]').fill("10")
            redrawn(page, before)
            page.mouse.move(*on_screen(page, *page.evaluate(CENTROID)))
            page.mouse.wheel(0, -150)
            page.wait_for_timeout(200)
            segment = page.evaluate("window.viewer.state.frame.results[0].segments[0]")
            x = (segment["start"][0] + segment["end"][0]) / 2
            y = (segment["start"][1] + segment["end"][1]) / 2
            page.mouse.click(*on_screen(page, x, y))
            page.locator("#panel").evaluate("panel => panel.scrollTo(0, 0)")
            page.screenshot(path=args.out)
            browser.close()
    finally:
        server.stop()
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
