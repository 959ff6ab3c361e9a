"""The grids of ``scanlines plot`` and ``scanlines demo`` (:func:`scanlines.viz.scans.plot_grid`)
carry one legend for all their panels, styled as the panels draw each kind."""

from __future__ import annotations

import re

import pytest

from cli_helpers import scanlines
from scanlines import Extractor
from scanlines.data import sample
from scanlines.io import open_log

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from scanlines.viz.scans import LEGEND_LABELS, plot_grid  # noqa: E402

LABELS = ["returns", "segments", "breakpoints", "corners", "outliers", "sensor"]


@pytest.fixture(scope="module")
def panels():
    extractor = Extractor("adaptive")
    with open_log(sample("intel")) as reader:
        scans = [scan for index, scan in reader.enumerate() if index in (0, 50, 100, 150)]
    return [(scan, extractor(scan), f"scan {k}") for k, scan in enumerate(scans)]


def test_a_grid_has_one_legend_naming_every_kind(panels):
    fig = plot_grid(panels, columns=2)
    try:
        assert len(fig.legends) == 1
        assert [t.get_text() for t in fig.legends[0].get_texts()] == LABELS
        assert list(LEGEND_LABELS) == LABELS
        assert all(ax.get_legend() is None for ax in fig.axes)  # one per figure, not per panel
        # drawn, inside the figure, above the panels
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        legend_box = fig.legends[0].get_window_extent(renderer)
        figure_box = fig.bbox
        assert figure_box.x0 <= legend_box.x0
        assert legend_box.x1 <= figure_box.x1
        assert legend_box.y1 <= figure_box.y1
        top_panel = max(ax.get_window_extent(renderer).y1 for ax in fig.axes)
        assert legend_box.y0 >= top_panel - 1
    finally:
        matplotlib.pyplot.close(fig)


def test_the_legend_symbols_are_those_of_the_panels(panels):
    fig = plot_grid(panels, columns=2)
    try:
        legend = {h.get_label(): h for h in fig.legends[0].legend_handles}
        drawn = {}
        for ax in fig.axes:
            for line in ax.get_lines():
                drawn.setdefault(line.get_label(), line)
        for kind in ("breakpoints", "corners", "outliers", "sensor"):
            assert legend[kind].get_marker() == drawn[kind].get_marker(), kind
            assert legend[kind].get_markeredgecolor() == drawn[kind].get_markeredgecolor(), kind
        assert legend["segments"].get_color() == drawn["segments"].get_color()
    finally:
        matplotlib.pyplot.close(fig)


def test_the_plot_command_writes_the_grid_with_its_legend(tmp_path):
    figure = tmp_path / "grid.svg"
    out = scanlines("plot", sample("intel"), "--scans", "0:300:50", "-o", figure)
    assert out.returncode == 0, out.stderr
    svg = figure.read_text()
    assert 'id="legend_1"' in svg
    legend = svg[svg.index('id="legend_1"') :]
    # matplotlib's SVG names each text it draws in a comment
    assert re.findall(r"<!-- (\w+) -->", legend)[: len(LABELS)] == LABELS
