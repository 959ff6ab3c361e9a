"""``scanlines ros2 --play LOG``: a log's scans on a LaserScan topic, its poses on ``/tf``."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import typer


def play_log(
    log: Path,
    rate: float | None,
    scans: str | None,
    on_error: str,
    topic: str,
    tf_topic: str,
    frame_id: str,
    odom_frame: str,
    domain_id: int,
    loopback: bool,
    wait: float,
    *,
    range_max: float | None = None,
) -> None:
    """Publish the scans of ``log`` (``topic`` and ``tf_topic`` resolved already), with a
    line on stderr at the first scan saying whether the log's poses go on ``/tf``, and a
    closing line of what was published."""
    from scanlines.cli.common import reader_options
    from scanlines.cli.log_reports import _with_breakdown
    from scanlines.errors import ParameterError
    from scanlines.io import open_log
    from scanlines.ros2 import Player
    from scanlines.runs.runner import parse_slice, select

    if on_error not in ("fail", "skip"):
        raise ParameterError(f"--on-error must be fail or skip, got {on_error!r}")
    selection = parse_slice(scans)
    skipped: Counter[str] = Counter()
    with open_log(log, options=reader_options(on_error=on_error, range_max=range_max)) as reader:
        # a missing or unreadable log fails before waiting for anyone
        player = Player(
            domain_id=domain_id,
            loopback=loopback,
            topic=topic,
            frame_id=frame_id,
            tf_topic=tf_topic,
            odom_frame=odom_frame,
        )
        if not player.wait_for_subscriber(wait):
            note = f"scanlines ros2: no subscriber on {topic} after {wait:g} s; playing"
            typer.echo(note, err=True)
        pairs = select(reader.enumerate(), selection)
        playable = _playable(pairs, log, on_error, skipped)
        count = player.play(_announced(playable, log, player), rate=rate)
        skipped.update(reader.skip_reasons)
    text = f"scanlines ros2: published {count} scans of {log.name} on {topic}"
    if player.transforms:
        text += f" and {player.transforms} transforms {odom_frame} -> {frame_id} on {tf_topic}"
    if on_error == "skip":
        text += f"; scan records skipped: {_with_breakdown(sum(skipped.values()), skipped)}"
    typer.echo(text, err=True)


def _announced(scans, log: Path, player):
    """``scans``, with one line on stderr at the first: its pose goes on ``/tf``, or why
    nothing does (the log has no poses: RViz then shows the scans in the laser's frame)."""
    first = True
    for scan in scans:
        if first:
            first = False
            if scan.pose is None:
                text = (
                    f"no {player.tf_topic}: {log.name} has no poses; in RViz, set the fixed "
                    f"frame to {player.frame_id}"
                )
            else:
                text = (
                    f"the log's poses on {player.tf_topic} as {player.odom_frame} -> "
                    f"{player.frame_id}, stamped as their scans; in RViz, set the fixed "
                    f"frame to {player.odom_frame}"
                )
            typer.echo(f"scanlines ros2: {text}", err=True)
        yield scan


def _playable(pairs, log: Path, on_error: str, skipped: Counter[str]):
    """The scans of ``pairs`` (index, scan) that a LaserScan can carry. A timestamp that is
    no ROS 2 time (before 1970, or past 2**31 - 1 s) stops the play with an error naming the
    log, the scan and the field, or with ``--on-error skip`` is counted in ``skipped``."""
    from scanlines.errors import LogFormatError
    from scanlines.ros2.convert import stamp_problem

    for index, scan in pairs:
        problem = stamp_problem(scan.timestamp or 0.0)
        if problem is None:
            yield scan
        elif on_error == "skip":
            skipped["timestamp"] += 1
        else:
            reason = f"{problem}; --on-error skip skips such scans"
            raise LogFormatError(
                reason, path=log, record=index, field="timestamp", unit="scan index"
            )
