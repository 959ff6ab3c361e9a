"""Picking a segment in the viewer, in real headless Chromium (the fixtures and helpers of
``test_viewer_browser.py``): its numbers are shown, and the selection goes when the view
changes."""

from __future__ import annotations

import numpy as np
import pytest

from test_viewer_browser import browser, frames, intel_server, page, redrawn

pytestmark = pytest.mark.slow  # headless Chromium
__all__ = ["browser", "intel_server", "page"]  # the fixtures, used by name


def click_first_segment(page) -> dict:
    """Click the middle of the first segment of configuration A; that segment."""
    segment = page.evaluate("window.viewer.state.frame.results[0].segments[0]")
    transform = page.evaluate("window.viewer.state.transform")
    box = page.locator("#view-0 canvas").bounding_box()
    middle = (np.array(segment["start"]) + np.array(segment["end"])) / 2
    x = box["x"] + transform["x"] + middle[0] * transform["scale"]
    y = box["y"] + transform["y"] - middle[1] * transform["scale"]
    page.mouse.click(x, y)
    return segment


def test_clicking_a_segment_shows_its_numbers(page):
    segment = click_first_segment(page)
    details = page.locator("#selection").inner_text()
    assert f"{segment['rho']:.4f} m" in details
    assert f"{segment['first']}..{segment['last']}" in details
    assert "var alpha" in details


def test_switching_to_the_world_view_clears_the_selected_segment(page):
    """A segment picked in the scan view is not one of the world view's: the selection
    goes, and does not come back with the scan view."""
    click_first_segment(page)
    assert page.evaluate("window.viewer.state.selected") is not None
    assert "var alpha" in page.locator("#selection").inner_text()
    before = frames(page)
    page.locator("#world-radio").check()
    redrawn(page, before)
    assert page.evaluate("window.viewer.state.selected") is None
    assert page.locator("#selection").inner_text() == "click a segment"
    before = frames(page)
    page.locator("input[name=view][value=scan]").check()
    redrawn(page, before)
    assert page.evaluate("window.viewer.state.selected") is None
    assert page.locator("#selection").inner_text() == "click a segment"
