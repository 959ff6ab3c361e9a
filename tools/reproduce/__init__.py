"""The paper's experiments, redone on the data scanlines ships: ``python -m tools.reproduce``.

:func:`reproduce` measures (:func:`tools.reproduce.experiments.run`, whose module
says what and how), draws the figures (:mod:`tools.reproduce.figures`) and writes the
page (:mod:`tools.reproduce.results_page`): ``<out>/RESULTS.md`` and
``<out>/figures/*.png``.

``import tools.reproduce`` needs numpy only; the figures import
matplotlib when they are drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from scanlines.evaluation.cases import LabelledFrameLike
from scanlines.outputs import write_text_atomically
from tools.reproduce.experiments import ReproduceConfig, ReproduceResult, Stage, run
from tools.reproduce.figures import write_figures
from tools.reproduce.results_page import render_markdown

__all__ = ["reproduce"]


def reproduce(
    out: str | Path = "docs",
    config: ReproduceConfig | None = None,
    *,
    labels: Sequence[LabelledFrameLike] | None = None,
    command: str = "python -m tools.reproduce",
    on_stage: Stage | None = None,
) -> tuple[ReproduceResult, list[Path]]:
    """:func:`~tools.reproduce.experiments.run`, then write ``<out>/RESULTS.md`` and
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
