"""The viewer end to end in real headless Chromium (Debian's ``chromium``, driven by
Playwright): what the page draws is what the library extracts.

In CI (``CI`` set) a missing browser fails these tests; elsewhere they are skipped. The
browser is ``$SCANLINES_CHROMIUM``, else ``chromium`` on the PATH. Screenshots go to
``test-artifacts/`` at the top of the repository.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from scanlines import Extractor, method_names
from scanlines.config import load_config
from scanlines.data import sample
from scanlines.runs.runner import log_profile
from viewer_helpers import serving

pytestmark = pytest.mark.slow  # headless Chromium

ARTIFACTS = Path(__file__).parent.parent / "test-artifacts"
#: The first scan's features are drawn (its returns come first, alone).
FEATURES_DRAWN = (
    "window.viewer && window.viewer.state.frame && window.viewer.state.frame.results.length > 0"
    " && window.viewer.stats.frames > 1"
)
#: Flags of a headless Chromium on a machine without network: no background connections.
CHROMIUM_FLAGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]  # fmt: skip


def chromium_path() -> str | None:
    return os.environ.get("SCANLINES_CHROMIUM") or shutil.which("chromium")


@pytest.fixture(scope="module")
def browser():
    executable = chromium_path()
    if executable is None:
        message = "no Chromium: install Debian's chromium (or set SCANLINES_CHROMIUM)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=CHROMIUM_FLAGS)
        yield browser
        browser.close()


@pytest.fixture(scope="module")
def intel_server():
    with serving(sample("intel")) as server:
        yield server


@pytest.fixture
def page(browser, intel_server):
    context = browser.new_context(viewport={"width": 1400, "height": 900}, accept_downloads=True)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(intel_server.url)
    page.wait_for_function(FEATURES_DRAWN)
    yield page
    context.close()
    assert not errors, errors


def frames(page) -> int:
    return page.evaluate("window.viewer.stats.frames")


def redrawn(page, before: int) -> dict:
    """Wait for a frame after ``before`` to be drawn; what it drew."""
    page.wait_for_function(f"window.viewer.stats.frames > {before}", timeout=60_000)
    page.wait_for_function("window.viewer.state.requested === window.viewer.state.drawn")
    return page.evaluate("window.viewer.stats.drawn")


def fact(page, key: str) -> str:
    return page.locator(f'#facts [data-fact="{key}"]').inner_text()


def param_input(page, panel: int, name: str):
    return page.locator(f'#config-{panel} input[aria-label="{name}"]')


@pytest.fixture(scope="module")
def intel_profile():
    return log_profile(sample("intel"), {})


def library_segments(scan_index: int, profile, method: str, **params) -> int:
    from scanlines.io import open_log

    with open_log(sample("intel")) as reader:
        scan = next(s for i, s in reader.enumerate() if i == scan_index)
    return len(Extractor(method, sensor_profile=profile, **params)(scan))


def test_page_loads_a_shipped_log_and_draws_its_first_scan(page, intel_profile):
    assert page.locator("#log-name").inner_text() == "intel_excerpt.clf.gz"
    page.wait_for_function("document.querySelector('#scan-count').textContent === '300'")
    drawn = page.evaluate("window.viewer.stats.drawn")
    assert drawn["index"] == 0
    assert drawn["segments"] == [library_segments(0, intel_profile, "adaptive")]
    assert page.locator("#legend").inner_text().count("\n") >= 4
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=ARTIFACTS / "viewer-first-scan.png")


def test_moving_the_slider_changes_the_scan_shown(page):
    first = page.evaluate("window.viewer.state.frame.x")
    before = frames(page)
    page.locator("#scan-slider").fill("150")
    drawn = redrawn(page, before)
    assert drawn["index"] == 150
    assert page.locator("#scan-index").input_value() == "150"
    assert fact(page, "segments-0") == str(drawn["segments"][0])
    assert page.evaluate("window.viewer.state.frame.x") != first


def test_parameter_changes_redraw_what_extract_returns_for_every_method(page, intel_profile):
    method_select = page.locator("#config-0 .method")
    for method in method_names():
        before = frames(page)
        method_select.select_option(method)
        redrawn(page, before)
        before = frames(page)
        param_input(page, 0, "min_points").fill("9")
        drawn = redrawn(page, before)
        expected = library_segments(0, intel_profile, method, min_points=9)
        assert drawn["segments"] == [expected], method
        assert fact(page, "segments-0") == str(expected)


def test_two_configurations_mark_their_differences(page, intel_profile):
    before = frames(page)
    page.locator("#compare").check()
    drawn = redrawn(page, before)
    assert drawn["differences"] == 0  # B starts as a copy of A
    before = frames(page)
    page.locator("#config-1 .method").select_option("split_merge")
    drawn = redrawn(page, before)
    assert drawn["segments"] == [
        library_segments(0, intel_profile, "adaptive"),
        library_segments(0, intel_profile, "split_merge"),
    ]
    assert drawn["differences"] > 0
    assert int(fact(page, "differing-0")) + int(fact(page, "differing-1")) == drawn["differences"]
    assert "differs between A and B" in page.locator("#legend").inner_text()
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=ARTIFACTS / "viewer-compare-overlay.png")
    before = frames(page)
    page.locator("#compare-mode").select_option("side")
    drawn = redrawn(page, before)
    assert page.locator("#view-1").is_visible()
    assert drawn["differences"] > 0
    page.screenshot(path=ARTIFACTS / "viewer-compare-side-by-side.png")


def world_view_of_the_last_300(page) -> dict:
    """Go to scan 299 and switch to the world view of the 300 scans up to it; what was drawn."""
    page.locator("#world-span").fill("300")
    before = frames(page)
    page.locator("#scan-slider").fill("299")
    redrawn(page, before)
    before = frames(page)
    page.locator("#world-radio").check()
    return redrawn(page, before)


def test_world_view_accumulates_the_scans_before(page):
    drawn = world_view_of_the_last_300(page)
    assert drawn["world"] == 300
    assert drawn["segments"][0] > 300


def test_copy_as_command_and_save_config_give_the_chosen_configuration(page, tmp_path):
    before = frames(page)
    page.locator("#config-0 .method").select_option("split_merge")
    redrawn(page, before)
    before = frames(page)
    param_input(page, 0, "min_length").fill("0.8")
    redrawn(page, before)
    page.locator("#config-0 .copy").click()
    command = page.locator("#config-0 .command")
    command.wait_for(state="visible")
    assert "--method split_merge" in command.inner_text()
    assert "--param min_length=0.8" in command.inner_text()
    with page.expect_download() as download:
        page.locator("#config-0 .save").click()
    saved = tmp_path / download.value.suggested_filename
    download.value.save_as(saved)
    config = load_config(saved)
    assert (config.method, dict(config.params)) == ("split_merge", {"min_length": 0.8})


def test_a_value_outside_the_domain_is_marked_and_not_sent(page):
    requested = page.evaluate("window.viewer.state.requested")
    field = param_input(page, 0, "min_length")
    field.fill("-2")
    assert "invalid" in (field.get_attribute("class") or "")
    page.wait_for_timeout(300)
    assert page.evaluate("window.viewer.state.requested") == requested
    assert page.locator("#error").is_hidden()


def test_a_malformed_record_stops_reading_with_a_message_on_the_page(browser):
    log = Path(__file__).parent / "io" / "fixtures" / "carmen_not_a_number.log"
    with serving(log) as server:
        page = browser.new_page()
        page.goto(server.url)
        page.wait_for_function(FEATURES_DRAWN)
        state = page.locator("#log-state")
        page.wait_for_function(
            "document.querySelector('#log-state').textContent.includes('1 scans')"
        )
        assert "reading stopped" in state.inner_text()
        assert "carmen_not_a_number.log" in state.inner_text()
        assert "line 3" in state.inner_text()
        assert page.evaluate("window.viewer.stats.drawn.index") == 0
        page.close()


# -- controls, legend and layout ----------------------------------------------------------

#: Canvas pixels that are drawn on (not transparent), in view A.
INKED_PIXELS = """() => {
  const canvas = document.querySelector('#view-0 canvas');
  const data = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
  let inked = 0;
  for (let i = 3; i < data.length; i += 4) if (data[i] > 0) inked += 1;
  return inked;
}"""


def layer_box(page, layer: str):
    return page.locator(f'#layers input[data-layer="{layer}"]')


@pytest.mark.parametrize(
    "layer", ["returns", "segments", "breakpoints", "corners", "outliers", "sensor"]
)
def test_each_layer_can_be_switched_off_and_on(page, layer):
    drawn = page.evaluate("window.viewer.stats.drawn")
    assert drawn["layers"][layer] > 0, drawn
    inked = page.evaluate(INKED_PIXELS)
    layer_box(page, layer).uncheck()
    drawn = page.evaluate("window.viewer.stats.drawn")
    assert drawn["layers"][layer] == 0
    shown = {name: n for name, n in drawn["layers"].items() if name not in (layer, "map")}
    assert all(n > 0 for n in shown.values()), drawn
    assert page.evaluate(INKED_PIXELS) < inked
    assert page.locator(f'#legend li[data-layer="{layer}"]').count() == 0
    layer_box(page, layer).check()
    assert page.evaluate("window.viewer.stats.drawn")["layers"][layer] > 0
    assert page.evaluate(INKED_PIXELS) == inked


#: Record every text the map's state line shows, in ``window.mapStates``.
MAP_STATES_SEEN = """() => {
  window.mapStates = [];
  const line = document.querySelector('#map-state');
  new MutationObserver(() => window.mapStates.push(line.textContent))
    .observe(line, { childList: true, characterData: true, subtree: true });
}"""


def map_line_on_screen(page, line: dict, pose) -> tuple[float, float]:
    """Where the page draws the middle of a map line: in the frame of the scan at ``pose``
    (or the world frame, ``None``), through the view's transform."""
    middle = (np.array(line["start"]) + np.array(line["end"])) / 2
    if pose is not None:
        x0, y0, theta = pose
        c, s = np.cos(theta), np.sin(theta)
        dx, dy = middle - (x0, y0)
        middle = np.array([c * dx + s * dy, -s * dx + c * dy])
    transform = page.evaluate("window.viewer.state.transform")
    box = page.locator("#view-0 canvas").bounding_box()
    return (
        box["x"] + transform["x"] + middle[0] * transform["scale"],
        box["y"] + transform["y"] - middle[1] * transform["scale"],
    )


def test_the_map_layer_draws_the_line_map_under_the_scan(page):
    assert not layer_box(page, "map").is_checked()  # off at start
    assert page.evaluate("window.viewer.stats.drawn.layers.map") == 0
    page.evaluate(MAP_STATES_SEEN)
    layer_box(page, "map").check()
    page.wait_for_function("window.viewer.state.mapState !== 'building'", timeout=120_000)
    assert page.evaluate("window.viewer.state.mapState") == "built"
    lines = page.evaluate("window.viewer.state.map.lines")
    assert len(lines) > 10
    assert page.evaluate("window.viewer.stats.drawn.layers.map") == len(lines)
    assert page.evaluate("window.viewer.stats.drawn.shapes.map") == "line"
    assert page.evaluate("window.mapStates")[0] == "building map…"
    assert f"{len(lines)} map lines" in page.locator("#map-state").inner_text()
    legend = page.locator('#legend li[data-layer="map"]')
    assert legend.inner_text() == "map lines"
    assert legend.locator("svg").get_attribute("data-shape") == "line"
    # drawn in the sensor frame of scan 0, in the map's colour, under its returns
    pose = page.evaluate("window.viewer.state.frame.pose")
    colour = page.evaluate("STROKES.map.colour")
    box = page.locator("#view-0 canvas").bounding_box()
    middles = [map_line_on_screen(page, line, pose) for line in lines]
    in_view = [(x, y) for x, y in middles if within(box, x, y)]
    assert len(in_view) > 3
    # (thin lines: on the transparent canvas a pixel they cross in part has their colour)
    assert sum(pixel_is(page, x, y, colour, 64) for x, y in in_view) > len(in_view) // 2
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=ARTIFACTS / "viewer-map-layer.png")
    drawn = world_view_of_the_last_300(page)
    assert drawn["layers"]["map"] == len(lines)
    page.screenshot(path=ARTIFACTS / "viewer-map-layer-world.png")
    layer_box(page, "map").uncheck()
    assert page.evaluate("window.viewer.stats.drawn.layers.map") == 0
    assert page.locator('#legend li[data-layer="map"]').count() == 0


def test_the_map_layer_of_a_log_without_poses_says_why(browser, tmp_path):
    from scanlines.viewer import ScanStore, ViewerServer, ViewerSession

    log = tmp_path / "scans.csv"
    log.write_text("1.0, 1.0, 1.0, 1.0\n2.0, 2.0, 2.0, 2.0\n")
    store = ScanStore(log, {"angle_min": -0.1, "angle_increment": 0.05})
    with ViewerServer(ViewerSession(store)) as server:
        page = browser.new_page()
        page.goto(server.url)
        page.wait_for_function(FEATURES_DRAWN)
        layer_box(page, "map").check()
        page.wait_for_function("window.viewer.state.mapState === 'failed'", timeout=60_000)
        message = "scans.csv has no poses: no line map"
        assert message in page.locator("#map-state").inner_text()
        assert message in page.locator("#error").inner_text()
        page.close()


def within(box: dict, x: float, y: float, margin: float = 5) -> bool:
    return (
        box["x"] + margin < x < box["x"] + box["width"] - margin
        and box["y"] + margin < y < box["y"] + box["height"] - margin
    )


def pixel_is(page, x: float, y: float, colour: str, min_alpha: int = 255) -> bool:
    """Whether the canvas pixel at page position ``(x, y)`` is ``colour`` (``#rrggbb``),
    covered at least ``min_alpha`` (a thin line covers the pixels it crosses in part)."""
    box = page.locator("#view-0 canvas").bounding_box()
    rgb = page.evaluate(
        """([x, y]) => {
          const canvas = document.querySelector('#view-0 canvas');
          const ratio = canvas.width / canvas.clientWidth;
          const data = canvas.getContext('2d').getImageData(x * ratio, y * ratio, 1, 1).data;
          return [data[0], data[1], data[2], data[3]];
        }""",
        [x - box["x"], y - box["y"]],
    )
    expected = [int(colour[k : k + 2], 16) for k in (1, 3, 5)]
    close = all(abs(a - b) <= 2 for a, b in zip(rgb[:3], expected, strict=True))
    return rgb[3] >= min_alpha and close


def test_the_legend_shows_the_symbol_each_layer_is_drawn_with(page):
    drawn_shapes = page.evaluate("window.viewer.stats.drawn.shapes")
    assert drawn_shapes == {
        "breakpoints": "circle", "corners": "diamond", "outliers": "cross", "sensor": "arrow",
    }  # fmt: skip
    legend = {}
    for entry in page.locator("#legend li").all():
        shape = entry.locator("svg").get_attribute("data-shape")
        legend.setdefault(entry.get_attribute("data-layer"), []).append(shape)
    for layer, shape in drawn_shapes.items():
        assert shape in legend[layer], (layer, legend)
    # the legend's icons are those shapes: a cross of two strokes, a four-cornered diamond
    assert page.locator('#legend li[data-layer="outliers"] svg path').count() == 1
    corner = page.locator('#legend li[data-layer="corners"] svg polygon').get_attribute("points")
    assert len(corner.split()) == 4
    assert "sensor pose" in page.locator("#legend").inner_text()


def test_the_fit_button_and_a_double_click_bring_back_the_initial_view(page):
    initial = page.evaluate("window.viewer.state.transform")
    canvas = page.locator("#view-0 canvas")
    box = canvas.bounding_box()
    page.mouse.move(box["x"] + 40, box["y"] + 60)
    for _ in range(8):
        page.mouse.wheel(0, 600)  # zoom far out, off centre
    page.mouse.move(box["x"] + 200, box["y"] + 200)
    page.mouse.down()
    page.mouse.move(box["x"] + 500, box["y"] + 400, steps=5)  # and pan away
    page.mouse.up()
    moved = page.evaluate("window.viewer.state.transform")
    assert moved["scale"] < initial["scale"] / 5
    assert page.locator("#fit").is_visible()
    assert "double-click" in page.locator("#view-tools").inner_text()
    page.locator("#fit").click()
    assert page.evaluate("window.viewer.state.transform") == pytest.approx(initial)
    page.mouse.move(box["x"] + 40, box["y"] + 60)
    page.mouse.wheel(0, 900)
    assert page.evaluate("window.viewer.state.transform")["scale"] < initial["scale"]
    canvas.dblclick(position={"x": 30, "y": 30})
    assert page.evaluate("window.viewer.state.transform") == pytest.approx(initial)


@pytest.fixture
def small_page(browser, intel_server):
    """The page in a 1280 x 800 window."""
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    page.goto(intel_server.url)
    page.wait_for_function(FEATURES_DRAWN)
    yield page
    context.close()


def within_window(box: dict, width: int = 1280, height: int = 800) -> bool:
    return (
        box["x"] >= 0 and box["y"] >= 0
        and box["x"] + box["width"] <= width + 0.5 and box["y"] + box["height"] <= height + 0.5
    )  # fmt: skip


@pytest.mark.parametrize("layout", ["overlay", "side"])
def test_configuration_b_fits_a_1280_by_800_window(small_page, layout):
    page = small_page
    before = frames(page)
    page.locator("#compare").check()
    redrawn(page, before)
    before = frames(page)
    page.locator("#compare-mode").select_option(layout)
    if layout != "overlay":
        redrawn(page, before)
    config_b = page.locator("#config-1")
    assert config_b.is_visible()
    for element in ("#config-0", "#config-1", "#view-0", "#legend", "#panel"):
        box = page.locator(element).bounding_box()
        assert within_window(box), (element, box)
    assert box["height"] > 150  # B's panel is not squeezed to nothing
    assert page.locator("#config-1 .method").is_visible()
    if layout == "side":
        assert within_window(page.locator("#view-1").bounding_box())
    # the page itself does not scroll: nothing is below or beside the window
    size = page.evaluate(
        "[document.documentElement.scrollWidth, document.documentElement.scrollHeight]"
    )
    assert size == [1280, 800]
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=ARTIFACTS / f"viewer-1280x800-compare-{layout}.png")


def relative_luminance(colour: str) -> float:
    channels = [int(colour[k : k + 2], 16) / 255 for k in (1, 3, 5)]
    linear = [c / 12.92 if c <= 0.03928 else ((c + 0.055) / 1.055) ** 2.4 for c in channels]
    return 0.2126 * linear[0] + 0.7152 * linear[1] + 0.0722 * linear[2]


def test_axis_labels_are_readable(page):
    font = page.evaluate("document.querySelector('#view-0 canvas').getContext('2d').font")
    assert float(font.split("px")[0]) >= 12, font
    colour = page.evaluate("window.viewer.stats.axis.colour")
    if len(colour) == 4:  # #rgb
        colour = "#" + "".join(c * 2 for c in colour[1:])
    contrast = 1.05 / (relative_luminance(colour) + 0.05)  # against the white canvas
    assert contrast >= 4.5, (colour, contrast)


def test_the_speed_control_sets_the_playback_interval(page):
    speeds = page.locator("#speed option").evaluate_all("options => options.map(o => o.value)")
    assert speeds == ["1", "5", "10", "20", "50"]
    page.locator("#speed").select_option("1")
    page.locator("#play").click()
    assert page.evaluate("window.viewer.state.playInterval") == 1000
    page.wait_for_timeout(1500)
    assert page.evaluate("window.viewer.state.index") <= 2  # at 1 scan/s: not 10 scans/s
    page.locator("#speed").select_option("50")  # while playing: at once
    assert page.evaluate("window.viewer.state.playInterval") == 20
    page.wait_for_function("window.viewer.state.index >= 10", timeout=20_000)
    page.locator("#play").click()
    assert page.locator("#play").inner_text() == "Play"


def test_world_view_says_which_poses_it_shows(page):
    assert page.locator("#pose-note").is_hidden()
    page.wait_for_function("window.viewer.state.log.finished")
    before = frames(page)
    page.locator("#world-radio").check()
    redrawn(page, before)
    note = page.locator("#pose-note")
    assert note.is_visible()
    # the Intel excerpt's FLASER poses: the reader cannot tell corrected from odometry
    assert note.inner_text() == "poses as recorded in the log (may be raw odometry)"
    page.locator('input[name=view][value="scan"]').check()
    assert note.is_hidden()


def param_row(page, name: str, panel: int = 0):
    return page.locator(f'#config-{panel} .param[data-param="{name}"]')


def choose(page, name: str, value: object, panel: int = 0) -> None:
    """Pick ``value`` of the choice parameter ``name`` (its option's value is JSON)."""
    import json

    param_row(page, name, panel).locator("select").select_option(json.dumps(value))


def fits_sideways(page, selector: str) -> bool:
    return page.locator(selector).evaluate("e => e.scrollWidth <= e.clientWidth")


@pytest.mark.parametrize("method", list(method_names()))
def test_the_form_fits_1400_by_900_and_shows_every_name_and_short_doc(page, method):
    before = frames(page)
    page.locator("#config-0 .method").select_option(method)
    redrawn(page, before)
    for selector in ("#configs", "#config-0"):
        assert fits_sideways(page, selector), selector
    rows = page.locator("#config-0 .params .param")
    assert rows.count() > 0
    for k in range(rows.count()):
        row = rows.nth(k)
        if not row.is_visible():
            continue
        name = row.get_attribute("data-param")
        label = row.locator(".name")
        assert label.inner_text() == name
        assert label.evaluate("e => e.scrollWidth <= e.clientWidth"), name  # not cut
        doc = row.locator(".doc").inner_text()
        assert 0 < len(doc) <= 45, (name, doc)
        assert row.evaluate("e => e.getBoundingClientRect().right") <= page.evaluate(
            "document.querySelector('#config-0').getBoundingClientRect().right"
        )
    if method == "adaptive":
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=ARTIFACTS / "viewer-1400x900-form.png")


def test_parameters_that_do_not_apply_are_hidden(page):
    rules = {
        "paper": {"k", "noise_k"},
        "abd": {"noise_k", "abd_lambda"},
        "pdbs": {"pdbs_c0"},
        "fixed": {"jump_distance"},
    }
    constants = {"k", "noise_k", "abd_lambda", "pdbs_c0", "jump_distance"}
    for rule, shown in rules.items():
        choose(page, "breakpoints", rule)
        for name in constants:
            assert param_row(page, name).is_visible() == (name in shown), (rule, name)
    choose(page, "denoise", "none")
    assert not param_row(page, "window").is_visible()
    assert not param_row(page, "min_cluster_points").is_visible()
    choose(page, "denoise", "paper")
    assert param_row(page, "window").is_visible()
    choose(page, "merge", False)  # a step switched off: its option hidden
    assert not param_row(page, "merge_chi2").is_visible()
    choose(page, "merge", True)
    assert param_row(page, "merge_chi2").is_visible()
    assert not param_row(page, "dkth_step").is_visible()  # dkth_range auto
    param_row(page, "dkth_range").locator('input[type="checkbox"]').uncheck()
    assert param_row(page, "dkth_step").is_visible()
    # another method: the first method's own parameters are gone
    page.locator("#config-0 .method").select_option("iepf")
    assert param_row(page, "denoise").count() == 0
    assert param_row(page, "split_distance").is_visible()


def test_the_noise_line_in_use_is_named(page, intel_profile):
    labels = page.locator("#facts tr td:first-child").all_inner_texts()
    assert "noise used: sensor profile" in labels
    assert "noise of this scan (not used)" in labels
    used = fact(page, "noise-used")
    assert used.startswith(f"{1000 * intel_profile.noise_sigma0:.1f} mm")
    assert f"{100 * intel_profile.noise_per_metre:.2f} % r" in used
    assert fact(page, "noise-scan") != used


def test_the_map_lines_lie_under_the_segments_and_are_thinner(page):
    layer_box(page, "map").check()
    page.wait_for_function("window.viewer.state.mapState === 'built'", timeout=120_000)
    page.wait_for_function("window.viewer.stats.drawn.layers.map > 0")
    drawn = page.evaluate("window.viewer.stats.drawn")
    assert drawn["order"][:2] == ["map", "segments"]  # the map first: under the segments
    assert drawn["widths"]["map"] < drawn["widths"]["segments"]
    legend = page.locator('#legend li[data-layer="map"] line').get_attribute("stroke-width")
    assert float(legend) == drawn["widths"]["map"]


def test_both_configurations_fit_1400_by_900(page):
    before = frames(page)
    page.locator("#compare").check()
    redrawn(page, before)
    for panel in (0, 1):
        choose(page, "breakpoints", "paper", panel)  # one more parameter shown
    for selector in ("#configs", "#config-0", "#config-1"):
        assert fits_sideways(page, selector), selector
    assert page.evaluate("document.documentElement.scrollWidth") == 1400
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=ARTIFACTS / "viewer-1400x900-compare.png")
