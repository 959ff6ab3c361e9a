"""What the log commands print: a log's description, a run's progress and its summary."""

from __future__ import annotations

import math


def _print_description(d) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=d.path, show_header=False)
    table.add_column("field", style="bold")
    table.add_column("value")

    def fmt(value, unit="", digits=3):
        if value is None:
            return "-"
        if not math.isfinite(value) or abs(value) >= 1e9:
            return f"{value:.4g}{unit}"
        return f"{value:.{digits}f}{unit}"

    reader = d.reader
    table.add_row("format", d.format)
    table.add_row("scans", str(d.scans))
    table.add_row("beams", ", ".join(f"{n} ({c} scans)" for n, c in sorted(d.beams.items())))
    table.add_row("field of view", ", ".join(f"{v:g} deg" for v in d.field_of_view_deg))
    table.add_row("resolution", ", ".join(f"{v:g} deg" for v in d.resolution_deg))
    table.add_row(
        "valid ranges",
        f"{fmt(d.range_min, ' m')} min, {fmt(d.range_mean, ' m')} mean, "
        f"{fmt(d.range_max, ' m')} max",
    )
    table.add_row(
        "no return", fmt(None if d.no_return_share is None else 100 * d.no_return_share, " %", 1)
    )
    if d.time_first is not None:
        table.add_row(
            "time",
            f"{_when(d.time_first, fmt)} .. {_when(d.time_last, fmt)} "
            f"(span {fmt(d.time_max - d.time_min, ' s')}, "
            f"{d.time_backwards_steps} steps backwards)",
        )
    else:
        table.add_row("time", "no timestamps")
    table.add_row("poses", f"{d.with_pose} of {d.scans} scans")
    if reader.get("topics"):
        table.add_row(
            "topics",
            "\n".join(
                f"{name}: {t['type']}, {t['messages']} messages"
                for name, t in sorted(reader["topics"].items())
            ),
        )
    if reader.get("topic"):
        table.add_row("topic", str(reader["topic"]))
    for note in reader.get("notes", []):
        table.add_row("note", note)
    if reader.get("records"):
        table.add_row(
            "records", ", ".join(f"{k} {v}" for k, v in sorted(reader["records"].items()))
        )
    if reader.get("skipped"):
        table.add_row(
            "skipped lines", ", ".join(f"{k} {v}" for k, v in sorted(reader["skipped"].items()))
        )
    if reader.get("errors"):
        table.add_row(
            "malformed records skipped",
            f"{_with_breakdown(reader['bad_scan_records'], reader['skip_reasons'])} scans, "
            f"{reader['bad_other_records']} others",
        )
    table.add_row("options", ", ".join(f"{k}={v}" for k, v in reader.get("options", {}).items()))
    Console().print(table)


#: Timestamps from this on (1990-01-01) are taken for Unix time and shown as UTC dates.
_EPOCH_LIKE = 631_152_000.0


def _when(stamp: float, fmt) -> str:
    """A timestamp: a UTC date and time for Unix time, else seconds (a log's own clock)."""
    import datetime

    if _EPOCH_LIKE <= stamp < 253_402_300_800:  # before the year 10000
        moment = datetime.datetime.fromtimestamp(stamp, tz=datetime.UTC)
        return moment.isoformat(timespec="milliseconds").replace("+00:00", "Z")
    return fmt(stamp, " s")


def _bins_text(profile) -> str:
    return "; ".join(
        f"{b.range:.2f} m: {1000 * b.sigma:.1f} +- {1000 * b.error:.1f} mm"
        for b in profile.noise_bins
    )


def _run_with_progress(reader, extractor, selection, out, frame, log, jobs, overwrite):
    from rich.console import Console
    from rich.progress import Progress

    from scanlines.runs.runner import run_log, run_log_to_file, selected_count

    total = selected_count(reader.scans_in_file, selection)
    columns = _progress_columns(total is not None)
    console = Console(stderr=True)  # off the terminal (logs, pipes) no bar and no blank line
    with Progress(
        *columns, console=console, transient=True, disable=not console.is_terminal
    ) as progress:
        task = progress.add_task(f"extracting {log.name}", total=total)

        def advance(_index: int) -> None:
            progress.advance(task)

        if out is None:
            summary = run_log(reader, extractor, scans=selection, on_scan=advance, jobs=jobs)
        else:
            summary = run_log_to_file(
                reader, extractor, out, frame=frame, scans=selection, on_scan=advance,
                input_name=str(log), jobs=jobs, overwrite=overwrite,
            )  # fmt: skip
    return summary


def _progress_columns(count_known: bool) -> tuple:
    """A bar with percentage, count and time left when the scan count is known; a
    spinner and the count so far when it is not."""
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        SpinnerColumn,
        TaskProgressColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    description = TextColumn("{task.description}")
    if count_known:
        return (
            description, BarColumn(), TaskProgressColumn(), MofNCompleteColumn(),
            TimeElapsedColumn(), TextColumn("left"), TimeRemainingColumn(),
        )  # fmt: skip
    return (SpinnerColumn(), description, TextColumn("{task.completed} scans"), TimeElapsedColumn())


def _print_summary(summary, out, notes=()) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{summary.method}: {summary.scans} scans", show_header=False)
    table.add_column("what", style="bold")
    table.add_column("value", justify="right")
    table.add_row("segments / scan", f"{summary.per_scan(summary.segments):.2f}")
    table.add_row("breakpoints / scan", f"{summary.per_scan(summary.breakpoints):.2f}")
    table.add_row("corners / scan", f"{summary.per_scan(summary.corners):.2f}")
    table.add_row("extraction, us / scan", f"{summary.microseconds_per_scan:.0f}")
    table.add_row(f"end to end, scans / s ({summary.jobs} jobs)", f"{summary.scans_per_second:.0f}")
    table.add_row(
        "scan records skipped", _with_breakdown(summary.skipped_scans, summary.skip_reasons)
    )
    table.add_row(
        "other records skipped", _with_breakdown(summary.skipped_other, summary.ignored_records)
    )
    table.add_row("output", str(out) if out is not None else "none (no --out given)")
    for note in notes:
        table.add_row("note", note)
    Console().print(table)


def _with_breakdown(total: int, parts: dict[str, int]) -> str:
    """``"42 (range 30, num_readings 12)"``, the largest parts first."""
    if not parts:
        return str(total)
    largest = sorted(parts.items(), key=lambda item: (-item[1], item[0]))[:4]
    more = ", ..." if len(parts) > 4 else ""
    return f"{total} ({', '.join(f'{k} {v}' for k, v in largest)}{more})"
