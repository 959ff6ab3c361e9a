"""``scanlines ros2 --play LOG``: a log's scans on a LaserScan topic, its odometry on ``/odom``
and ``/tf``, the laser's mounting on ``/tf_static``."""

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
    restamp: bool = False,
    odom_topic: str = "/odom",
    tf_static_topic: str = "/tf_static",
    base_frame: str = "base_link",
    range_max: float | None = None,
) -> None:
    """Publish the scans of ``log`` (the topics resolved already), with a line on stderr
    where the log's stamps step back (read through once first), a line at the first scan
    saying whether the log's odometry goes on ``/odom`` and ``/tf``, and a closing line of
    what was published. ``restamp``: stamps that only go forward (:func:`~scanlines.ros2.
    player.monotonic_stamps`)."""
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
    # a missing or unreadable log fails before waiting for anyone
    times, mounting = _first_pass(log, selection, on_error)
    stamps = _stamps_note(times, restamp)
    with open_log(log, options=reader_options(on_error=on_error, range_max=range_max)) as reader:
        player = Player(
            domain_id=domain_id,
            loopback=loopback,
            topic=topic,
            frame_id=frame_id,
            tf_topic=tf_topic,
            odom_frame=odom_frame,
            odom_topic=odom_topic,
            tf_static_topic=tf_static_topic,
            base_frame=base_frame,
        )
        if not player.wait_for_subscriber(wait):
            note = f"scanlines ros2: no subscriber on {topic} after {wait:g} s; playing"
            typer.echo(note, err=True)
        pairs = select(reader.enumerate(), selection)
        playable = _playable(pairs, log, on_error, skipped)
        count = player.play(
            _announced(playable, log, player), rate=rate, stamps=stamps, mounting=mounting
        )
        skipped.update(reader.skip_reasons)
    text = f"scanlines ros2: published {count} scans of {log.name} on {topic}"
    if player.transforms:
        text += (
            f" and {player.transforms} odometry poses {odom_frame} -> {base_frame} on "
            f"{odom_topic} and {tf_topic}"
        )
    if on_error == "skip":
        text += f"; scan records skipped: {_with_breakdown(sum(skipped.values()), skipped)}"
    typer.echo(text, err=True)


def _first_pass(log: Path, selection: slice, on_error: str):
    """The timestamps of the scans to play, and the laser's mounting on the robot as the
    first scan's record gives it (CARMEN's laser and odometry poses), else ``None``."""
    from scanlines.cli.common import reader_options
    from scanlines.io import open_log
    from scanlines.runs.runner import select

    times: list[float | None] = []
    mounting = None
    with open_log(log, options=reader_options(on_error=on_error)) as reader:
        for scan in _playable(select(reader.enumerate(), selection), log, on_error, Counter()):
            if not times:
                mounting = getattr(reader, "recorded_mounting", None)
            times.append(scan.timestamp)
    return times, mounting


def _stamps_note(times: list, restamp: bool) -> list[float] | None:
    """The stamps to publish (``None``: the log's), with one line on stderr when the
    log's step back."""
    from scanlines.ros2.player import monotonic_stamps, steps_back

    count, largest = steps_back(times)
    if count:
        times_text = "once" if count == 1 else f"{count:,} times"
        text = (
            f"the log's stamps step back or stand still {times_text} (by up to "
            f"{largest:.3f} s): tf2 and RViz drop or reset on that; "
        )
        text += (
            "publishing --restamp'ed stamps (the log's intervals where positive, the median "
            "positive interval where a step goes back)"
            if restamp
            else "--restamp publishes stamps that only go forward"
        )
        typer.echo(f"scanlines ros2: {text}", err=True)
    return monotonic_stamps(times) if restamp else None


def _announced(scans, log: Path, player):
    """``scans``, with one line on stderr at the first: its odometry goes on ``/odom`` and
    ``/tf``, or why nothing does (the log has no poses: RViz then shows the scans in the
    laser's frame)."""
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
                    f"the log's odometry on {player.odom_topic} and {player.tf_topic} as "
                    f"{player.odom_frame} -> {player.base_frame}, stamped as their scans, "
                    f"the mounting on {player.tf_static_topic} as {player.base_frame} -> "
                    f"{player.frame_id}; in RViz, set the fixed frame to {player.odom_frame}"
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
