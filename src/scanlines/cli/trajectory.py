"""``scanlines eval trajectory EST --reference REF``: a trajectory's ATE and RPE."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from scanlines.cli.common import guarded


def register(group: typer.Typer) -> None:
    group.command(
        "trajectory",
        help="Score an estimated trajectory against a reference: ATE after a rigid 2-D "
        "alignment and RPE per metre travelled, poses matched within 10 ms (as evo). Writes "
        "trajectory_eval.json into --out (or to --out if it ends in .json).",
    )(guarded(evaluate_trajectory_command))


def evaluate_trajectory_command(
    estimate: Annotated[
        Path,
        typer.Argument(
            metavar="ESTIMATE",
            help="The estimated trajectory: a TUM file (.tum, .txt) or a log's poses.",
        ),
    ],
    reference: Annotated[
        Path | None,
        typer.Option(help="The reference: a TUM file (.tum, .txt) or a log with poses."),
    ] = None,
    out: Annotated[
        Path, typer.Option(help="Folder for trajectory_eval.json, or a .json file.")
    ] = Path("scanlines-eval"),
) -> None:
    """Print the table of ``estimate`` against ``reference`` and write it as JSON."""
    from rich.console import Console
    from rich.table import Table

    from scanlines.cli.progress import progress
    from scanlines.evaluation.trajectory import load_trajectory, trajectory_error
    from scanlines.map.export import dumps, naming_output
    from scanlines.outputs import write_text_atomically

    if reference is None:
        from scanlines.errors import ParameterError

        raise ParameterError("eval trajectory needs --reference (a TUM file or a log with poses)")
    with progress(f"reading {estimate.name} and {reference.name}", unit=None):
        score = trajectory_error(load_trajectory(estimate), load_trajectory(reference))
    table = Table(title=f"{score.estimate} against {score.reference}", show_header=False)
    table.add_column("what", style="bold")
    table.add_column("value", justify="right")

    def mm(value: float | None) -> str:
        return "-" if value is None else f"{1000 * value:.1f}"

    rows = [
        ("poses: estimate / reference / matched (10 ms)",
         f"{score.estimate_poses} / {score.reference_poses} / {score.matched}"),
        ("clock steps back: estimate / reference",
         f"{score.estimate_steps_back} / {score.reference_steps_back}"),
        ("reference path, m", f"{score.path_length:.1f}"),
        ("ATE RMSE / mean / median / max, mm",
         " / ".join(mm(v) for v in (score.ate_rmse, score.ate_mean, score.ate_median,
                                    score.ate_max))),
        ("ATE rotation RMSE, deg", f"{score.ate_rotation_rmse_deg:.2f}"),
        (f"RPE per {score.delta:g} m: pairs", f"{score.rpe_pairs}"),
        (f"RPE per {score.delta:g} m: RMSE / mean / max, mm",
         " / ".join(mm(v) for v in (score.rpe_rmse, score.rpe_mean, score.rpe_max))),
        (f"RPE per {score.delta:g} m: rotation RMSE, deg",
         "-" if score.rpe_rotation_rmse_deg is None else f"{score.rpe_rotation_rmse_deg:.2f}"),
    ]  # fmt: skip
    for row in rows:
        table.add_row(*row)
    Console().print(table)
    path = out if out.suffix.lower() == ".json" else out / "trajectory_eval.json"
    with naming_output(path, "the trajectory's score"):
        write_text_atomically(path, dumps(score.to_dict()), make_folder=True)
    typer.echo(f"wrote {path}")
