"""ROS 1 bags and ROS 2 bags (sqlite3 or mcap storage) with ``sensor_msgs/msg/LaserScan``.

Read with ``rosbags.highlevel.AnyReader``, imported only when a bag is opened
(``import scanlines.io`` does not import rosbags). Accepted paths: a ROS 1
``.bag`` file; a ROS 2 bag directory (with ``metadata.yaml``, or holding a
single ``.db3``/``.mcap`` file); a bare ``.db3`` or ``.mcap`` file.

Topic: the ``topic`` option, else the only ``LaserScan`` topic of the bag. A
bag with several ``LaserScan`` topics and no ``topic`` option, or with none,
raises :class:`~scanlines.LogFormatError` listing what is there.

Per message:

* ranges are passed through unchanged (float32 widened exactly to float64),
  so REP 117's ``-inf`` (too close), ``NaN`` (measurement error) and ``+inf``
  (no return) all reach :class:`~scanlines.Scan`, which treats them as invalid;
* ``angle_min``, ``angle_increment``, ``range_min``, ``range_max`` and
  ``intensities`` (when there is one per beam) come from the message;
* ``timestamp`` is the header stamp in seconds, or the bag's receive time when
  the stamp is zero;
* ``pose`` is ``None`` (TF is not read).

Record numbers in errors are 1-based message numbers within the topic.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

from scanlines.errors import LogFormatError, ScanError, describe
from scanlines.io.base import (
    DEFAULT_MAX_BEAMS,
    DEFAULT_MAX_RECORD_BYTES,
    ErrorPolicy,
    LogReader,
)
from scanlines.scan import Scan

__all__ = ["LASERSCAN_TYPES", "RosbagReader", "is_ros2_bag_dir"]

#: Message type names of ``LaserScan`` in ROS 2 and ROS 1 (as rosbags names them).
LASERSCAN_TYPES = ("sensor_msgs/msg/LaserScan",)
_STORAGE_SUFFIXES = (".db3", ".mcap")


def is_ros2_bag_dir(path: Path) -> bool:
    """True for a directory with ``metadata.yaml`` or with ``.db3``/``.mcap`` storage files."""
    if not path.is_dir():
        return False
    return (path / "metadata.yaml").exists() or any(
        child.suffix in _STORAGE_SUFFIXES for child in path.iterdir()
    )


def _bag_paths(path: Path) -> list[Path]:
    """The path(s) to hand to AnyReader (a directory without metadata: its storage file)."""
    if path.is_dir() and not (path / "metadata.yaml").exists():
        storage = sorted(c for c in path.iterdir() if c.suffix in _STORAGE_SUFFIXES)
        if len(storage) != 1:
            raise LogFormatError(
                f"a ROS 2 bag directory without metadata.yaml must hold exactly one .db3/.mcap "
                f"file, found {len(storage)}",
                path=path,
            )
        return storage
    return [path]


class RosbagReader(LogReader):
    """Stream the ``LaserScan`` messages of one topic of a ROS 1 or ROS 2 bag.

    Parameters
    ----------
    path:
        ``.bag`` file, ROS 2 bag directory, or ``.db3``/``.mcap`` file.
    topic:
        The ``LaserScan`` topic; ``None`` picks the only one.
    on_error:
        ``"fail"`` or ``"skip"`` messages that do not make a valid scan.
    max_beams, max_record_bytes:
        Limits of one record (:mod:`scanlines.io.base`).

    Attributes
    ----------
    topics : dict
        Every topic of the bag: name -> ``(message type, message count)``.
    topic : str
        The topic read.

    Raises
    ------
    LogFormatError
        When the bag cannot be opened, holds no ``LaserScan`` topic, holds
        several and ``topic`` is not given, or ``topic`` is not a ``LaserScan``
        topic of the bag.
    """

    format_name = "rosbag"
    record_unit = "message"

    def __init__(
        self,
        path: str | Path,
        *,
        topic: str | None = None,
        on_error: ErrorPolicy = "fail",
        max_beams: int = DEFAULT_MAX_BEAMS,
        max_record_bytes: int = DEFAULT_MAX_RECORD_BYTES,
    ) -> None:
        super().__init__(
            path, on_error=on_error, max_beams=max_beams, max_record_bytes=max_record_bytes
        )
        self._paths = _bag_paths(self.path)
        with self._open() as reader:
            self.ros_version = 2 if reader.is2 else 1
            self.topics = _topic_table(reader)
        self.topic = self._choose_topic(topic)

    @property
    def laserscan_topics(self) -> list[str]:
        """The bag's ``LaserScan`` topics, sorted."""
        return sorted(t for t, (msgtype, _) in self.topics.items() if msgtype in LASERSCAN_TYPES)

    def _choose_topic(self, topic: str | None) -> str:
        candidates = self.laserscan_topics
        if topic is not None:
            if topic not in candidates:
                raise LogFormatError(
                    f"topic {topic!r} is not a LaserScan topic of this bag; "
                    f"LaserScan topics: {', '.join(candidates) or 'none'}",
                    path=self.path,
                    field="topic",
                )
            return topic
        if not candidates:
            listed = ", ".join(f"{t} ({m})" for t, (m, _) in sorted(self.topics.items()))
            raise LogFormatError(
                f"no sensor_msgs/msg/LaserScan topic in this bag (topics: {listed or 'none'})",
                path=self.path,
            )
        if len(candidates) > 1:
            raise LogFormatError(
                f"several LaserScan topics: {', '.join(candidates)}; choose one with topic=...",
                path=self.path,
                field="topic",
            )
        return candidates[0]

    @contextmanager
    def _open(self) -> Iterator[Any]:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore

        store = Stores.ROS1_NOETIC if self._paths[0].suffix == ".bag" else Stores.ROS2_HUMBLE
        try:
            reader = AnyReader(self._paths, default_typestore=get_typestore(store))
            reader.open()
        except Exception as exc:  # rosbags raises many unrelated types on a damaged bag
            raise LogFormatError(f"cannot open the bag ({describe(exc)})", path=self.path) from None
        try:
            yield reader
        finally:
            with suppress(Exception):
                reader.close()

    def options(self) -> dict[str, Any]:
        """Resolved options: the topic read."""
        return {**super().options(), "topic": self.topic}

    def info(self) -> dict[str, Any]:
        """Reader metadata plus the bag's topics and the scan count of the topic read."""
        return {
            **super().info(),
            "ros_version": self.ros_version,
            "topic": self.topic,
            "topics": {t: {"type": m, "messages": n} for t, (m, n) in sorted(self.topics.items())},
            "scans_in_file": self.topics[self.topic][1],
        }

    def _scans(self) -> Iterator[tuple[int, Scan]]:
        with self._open() as reader:
            connections = [c for c in reader.connections if c.topic == self.topic]
            index = -1
            for index, (connection, bag_time, raw) in enumerate(self._guarded(reader, connections)):
                try:
                    message = reader.deserialize(raw, connection.msgtype)
                    scan = self._scan(message, bag_time, index + 1)
                except LogFormatError as error:
                    self._bad_record(error)
                    continue
                except Exception as exc:  # a damaged message: any decoding error
                    self._bad_record(
                        LogFormatError(
                            f"cannot decode ({describe(exc)})",
                            path=self.path,
                            record=index + 1,
                            unit="message",
                        )
                    )
                    continue
                self.counts[self.topic] += 1
                yield index, scan
            self._account_for_every_message(read=index + 1)
            for topic in self.topics:
                if topic != self.topic:
                    self.skipped[topic] = self.topics[topic][1]

    def _guarded(self, reader: Any, connections: list[Any]) -> Iterator[Any]:
        """The topic's messages, a storage error mid-stream turned into a LogFormatError."""
        count = 0
        try:
            for item in reader.messages(connections):
                count += 1
                yield item
        except Exception as exc:  # rosbags raises several unrelated types here
            raise LogFormatError(
                f"the bag is damaged after message {count} of {self.topic} ({describe(exc)})",
                path=self.path,
                record=count + 1,
                unit="message",
            ) from None

    def _account_for_every_message(self, read: int) -> None:
        """The bag's index says how many messages the topic has: fewer read is damage,
        an error (or, in skip mode, that many skipped records), never a short result."""
        msgtype, declared = self.topics[self.topic]
        if read >= declared:  # more than declared: the count was wrong, nothing is lost
            self.topics[self.topic] = (msgtype, read)
            return
        missing = declared - read
        error = LogFormatError(
            f"the bag declares {declared} messages on {self.topic} but only {read} could be "
            f"read: {missing} lost to damage",
            path=self.path,
            record=read + 1,
            unit="message",
        )
        self._bad_record(error, count=missing)

    def _scan(self, message: Any, bag_time: int, record: int) -> Scan:
        self._check_beams(len(message.ranges), record)
        try:
            return Scan.from_laserscan(message, fallback_time=bag_time * 1e-9)
        except ScanError as exc:
            field = str(exc).split(" ", 1)[0]
            raise LogFormatError(
                str(exc), path=self.path, record=record, field=field, unit="message"
            ) from None


def _topic_table(reader: Any) -> dict[str, tuple[str, int]]:
    """Topic -> (message type, message count the bag declares). A count that is not a
    non-negative integer (a damaged ``metadata.yaml``) counts as 0: nothing is declared."""
    table: dict[str, tuple[str, int]] = {}
    for connection in reader.connections:
        msgtype, count = table.get(connection.topic, (connection.msgtype, 0))
        declared = connection.msgcount
        if isinstance(declared, bool) or not isinstance(declared, int) or declared < 0:
            declared = 0
        table[connection.topic] = (msgtype, count + declared)
    return table
