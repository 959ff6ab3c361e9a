"""The paper's experiments, redone on the data scanlines ships: ``scanlines reproduce``.

The one place where measuring (:mod:`scanlines.evaluation`) and drawing
(:mod:`scanlines.viz`) meet, so it stands above both.

:func:`reproduce` measures (:func:`scanlines.evaluation.experiments.run`, whose module
says what and how), draws the figures (:mod:`scanlines.viz.reproduce`) and writes the
page (:mod:`scanlines.evaluation.results_page`): ``<out>/RESULTS.md`` and
``<out>/figures/*.png``.

``import scanlines.reproduce`` needs numpy only; the figures import
matplotlib when they are drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from scanlines.evaluation.cases import LabelledFrameLike
from scanlines.evaluation.experiments import ReproduceConfig, ReproduceResult, Stage, run
from scanlines.evaluation.results_page import render_markdown
from scanlines.outputs import write_text_atomically
from scanlines.viz.reproduce import write_figures

__all__ = ["reproduce"]


def reproduce(
    out: str | Path = "docs",
    config: ReproduceConfig | None = None,
    *,
    labels: Sequence[LabelledFrameLike] | None = None,
    command: str = "scanlines reproduce",
    on_stage: Stage | None = None,
) -> tuple[ReproduceResult, list[Path]]:
    """:func:`~scanlines.evaluation.experiments.run`, then write ``<out>/RESULTS.md`` and
    ``<out>/figures/*.png``.

    Returns the result and the written paths (markdown first).
    """
    result = run(config, labels=labels, command=command, on_stage=on_stage)
    if on_stage is not None:
        on_stage("figures and RESULTS.md")
    out = Path(out)
    figures = write_figures(result, out / "figures")
    names = {key: path.name for key, path in figures.items()}
    md = write_text_atomically(out / "RESULTS.md", render_markdown(result, names), make_folder=True)
    return result, [md, *figures.values()]
