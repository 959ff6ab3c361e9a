"""``scanlines run`` on several logs: a Parquet dataset (``scanlines.runs.fleet``), or one output
per log; one summary of them all."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from scanlines.errors import ParameterError
from scanlines.reader_options import ReaderOptions

#: Exit code when some logs failed (the others are written).
SOME_FAILED = 2


def run_many(
    logs: list[Path],
    out: Path | None,
    output_format: str | None,
    *,
    method: str,
    preset: str | None,
    params: dict[str, Any],
    options: ReaderOptions,
    sensor_profile: Path | None,
    jobs: int,
    scheduler: str | None,
    chunk_records: int,
    overwrite: bool,
    scans: str | None,
    frame: str,
) -> None:
    if out is None:
        raise ParameterError("several logs need --out DIR (a folder, or a .parquet dataset)")
    output_format = output_format or ("parquet" if out.suffix.lower() == ".parquet" else "jsonl")
    if output_format != "parquet":
        if scheduler is not None:
            raise ParameterError("--scheduler writes a parquet dataset: add --format parquet")
        summary = _one_output_per_log(
            logs, out, output_format, method, preset, params, options, sensor_profile, jobs,
            overwrite, scans, frame,
        )  # fmt: skip
    else:
        if scans is not None or frame != "sensor":
            raise ParameterError("a parquet dataset holds every scan in the sensor frame")
        from scanlines.runs.fleet import run_fleet

        with _progress() as advance:
            summary = run_fleet(
                logs, out, method=method, preset=preset, params=params,
                reader_options=options, sensor_profile=sensor_profile, jobs=jobs,
                scheduler=scheduler, chunk_records=chunk_records, overwrite=overwrite,
                on_chunk=advance,
            )  # fmt: skip
    _print(summary, out)
    if summary.failed:
        raise typer.Exit(SOME_FAILED)


def _one_output_per_log(logs, out, output_format, method, preset, params, options,
                        sensor_profile, jobs, overwrite, scans, frame):  # fmt: skip
    """Each log to ``out/NAME.FORMAT``, one after the other, with ``jobs`` threads each."""
    import time

    from scanlines.cli.common import profile_for_run, with_mounting
    from scanlines.errors import ScanlinesError
    from scanlines.extractor import Extractor
    from scanlines.io import open_log
    from scanlines.runs.fleet import FleetSummary, LogOutcome, expand_inputs, log_names
    from scanlines.runs.runner import parse_slice, run_log_to_file

    if not out.is_dir():
        raise ParameterError(f"{out}: several logs are written into a folder that exists")
    selection = parse_slice(scans)
    paths = expand_inputs(logs)
    summary = FleetSummary(engine=f"one log at a time, {jobs} threads")
    started = time.perf_counter()
    Extractor(method, preset, **params)  # checks the parameters before any log is read
    for name, path in zip(log_names(paths), paths, strict=True):
        outcome = LogOutcome(name, str(path))
        try:
            profile = profile_for_run(path, options, selection, sensor_profile)
            extractor = Extractor(method, preset, sensor_profile=profile, **params)
            log_options = with_mounting(path, options, profile) if frame == "world" else options
            with open_log(path, options=log_options) as reader:
                result = run_log_to_file(reader, extractor, out / f"{name}.{output_format}",
                                         frame=frame, scans=selection, jobs=jobs,
                                         overwrite=overwrite)  # fmt: skip
            outcome.scans, outcome.segments = result.scans, result.segments
            outcome.skipped_scans, outcome.seconds = result.skipped_scans, result.total_seconds
        except (ScanlinesError, OSError) as error:
            outcome.status, outcome.reason = "failed", str(error)
        summary.logs.append(outcome)
    summary.seconds = time.perf_counter() - started
    return summary


class _progress:
    """A progress line counting finished scans (stderr), for the fleet path."""

    def __enter__(self):
        from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        self.display = Progress(SpinnerColumn(), TextColumn("{task.description}"),
                                TimeElapsedColumn(), transient=True)  # fmt: skip
        self.task = self.display.add_task("extracting", total=None)
        self.scans = 0
        self.display.start()
        return self.advance

    def advance(self, result) -> None:
        self.scans += result.scans
        self.display.update(self.task, description=f"extracting: {self.scans} scans done")

    def __exit__(self, *exc: object) -> None:
        self.display.stop()


def _print(summary, out: Path) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{len(summary.logs)} logs -> {out} ({summary.engine})")
    for column in ("log", "status", "scans", "segments", "skipped scans", "seconds"):
        table.add_column(column, justify="left" if column in ("log", "status") else "right")
    for log in summary.logs:
        table.add_row(log.log, log.status, str(log.scans), str(log.segments),
                      str(log.skipped_scans), f"{log.seconds:.1f}")  # fmt: skip
    Console().print(table)
    for log in summary.failed:
        typer.echo(f"failed: {log.log}: {log.reason}")
        typer.echo(f"scanlines: error: {log.log}: {log.reason}", err=True)
    done = [log for log in summary.logs if log.status == "done"]
    scans = sum(log.scans for log in done)
    rate = scans / summary.seconds if summary.seconds else 0.0
    typer.echo(
        f"{scans} scans extracted in {summary.seconds:.1f} s ({rate:.0f} scans/s); "
        f"{len(summary.logs) - len(done) - len(summary.failed)} logs done before; "
        f"{len(summary.failed)} of {len(summary.logs)} failed"
    )
