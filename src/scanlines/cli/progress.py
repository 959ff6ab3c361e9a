"""A transient progress display on stderr when it is a terminal; nothing at all otherwise."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


class Ticker:
    """The callbacks the library's hooks take, moving one progress task: ``scan(index)``
    (one more unit), ``update(done, total)``, ``stage(description, done, total)`` and
    ``begin(description)``."""

    def __init__(self, bar, task, description: str) -> None:
        self.bar, self.task, self.description = bar, task, description

    def scan(self, _index: object = None) -> None:
        self.bar.advance(self.task)

    def update(self, done: int, total: int | None) -> None:
        self.bar.update(self.task, completed=done, total=total)

    def stage(self, description: str, done: int, total: int | None) -> None:
        self.description = description
        self.bar.update(self.task, description=description, completed=done, total=total)

    def begin(self, description: str) -> None:
        """A new stage of the same count: the count starts again from 0."""
        if description != self.description:
            self.description = description
            self.bar.update(self.task, description=description, completed=0)


@contextmanager
def progress(
    description: str, total: int | None = None, unit: str | None = "scans"
) -> Iterator[Ticker]:
    """A transient bar with the count of ``unit`` done (of ``total``, with the time left,
    when known) and the time taken, or with ``unit`` ``None`` a spinner and the time
    alone; on stderr, drawn only when stderr is a terminal: piped or logged, a command
    prints exactly what it printed without it."""
    from rich.console import Console
    from rich.progress import Progress

    console = Console(stderr=True)
    with Progress(
        *_columns(unit), console=console, transient=True, disable=not console.is_terminal
    ) as bar:
        yield Ticker(bar, bar.add_task(description, total=total), description)


def _columns(unit: str | None) -> tuple:
    """Description, bar (a pulse while the total is not known), count, elapsed, left."""
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        SpinnerColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    if unit is None:
        return SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn()

    class TimeLeft(TimeRemainingColumn):
        """``left H:MM:SS`` once the total is known; nothing before."""

        def render(self, task):
            from rich.text import Text

            if task.total is None:
                return Text("")
            return Text.assemble("left ", super().render(task))

    return (
        SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
        TextColumn(unit), TimeElapsedColumn(), TimeLeft(),
    )  # fmt: skip
