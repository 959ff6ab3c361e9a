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

A ROS 1 bag is also walked record by record when opened
(:mod:`scanlines.io.rosbag1`). Where its index disagrees with what its chunks
hold (a lowered ``chunk_count``, a zeroed chunk-info ``count``), cannot be read,
or is missing (a recording cut short), the bag is read by its chunks, as
``rosbag reindex`` would, and ``info()["index_note"]`` says why. Damage (or the
end of a truncated file) is reported at its byte offset, with the messages read
before it and those the index lists that are lost; ``on_error="skip"`` reads on
past it.
"""

from __future__ import annotations

from collections import Counter
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
from scanlines.io.mcap_records import check_mcap_records
from scanlines.io.rosbag_files import _bag_paths, _storage_bytes, is_ros2_bag_dir
from scanlines.scan import Scan

__all__ = ["LASERSCAN_TYPES", "RosbagReader", "is_ros2_bag_dir"]

#: Message type names of ``LaserScan`` in ROS 2 and ROS 1 (as rosbags names them).
LASERSCAN_TYPES = ("sensor_msgs/msg/LaserScan",)
#: Fewest bytes a stored message takes (a serialized empty ``LaserScan`` takes more).
MIN_MESSAGE_BYTES = 32


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
        #: ROS 1: the bag as its chunks hold it, when its index disagrees (else None).
        self._layout: Any = None
        #: What was found wrong with a ROS 1 bag's index (for ``info``), or None.
        self.index_note: str | None = None
        if self._paths[0].suffix == ".bag" and self._paths[0].is_file():
            self.ros_version = 1
            self.topics = self._ros1_topics()
        else:
            check_mcap_records(self.path)  # where a record is damaged, before rosbags
            with self._open() as reader:
                self.ros_version = 2 if reader.is2 else 1
                self.topics = _topic_table(reader, self.path)
            self._drop_impossible_counts()
        self.topic = self._choose_topic(topic)

    def _drop_impossible_counts(self) -> None:
        """A declared count the storage could not hold (more messages than its bytes over
        :data:`MIN_MESSAGE_BYTES`: a damaged ``metadata.yaml``) declares nothing, like a
        count that is not a number; ``index_note`` says so. The messages read are then
        all there is, and no absurd number is reported as skipped."""
        stored = sum(_storage_bytes(p) for p in self._paths)
        most = stored // MIN_MESSAGE_BYTES
        for topic, (msgtype, declared) in list(self.topics.items()):
            if declared > most:
                self.topics[topic] = (msgtype, 0)
                note = (
                    f"the bag declares {declared} messages on {topic}, more than its "
                    f"{stored} bytes of storage could hold: the count is ignored"
                )
                self.index_note = note if self.index_note is None else f"{self.index_note}; {note}"

    def _ros1_topics(self) -> dict[str, tuple[str, int]]:
        """The topic table of a ROS 1 bag. The bag is walked record by record (as
        ``rosbag reindex`` would); where its index disagrees with what the chunks hold,
        or cannot be read, the bag is read by its chunks (:mod:`scanlines.io.rosbag1`)."""
        from scanlines.io.rosbag1 import walk

        try:
            layout = walk(self._paths[0])
        except OSError as exc:
            raise LogFormatError(f"cannot read the bag ({describe(exc)})", path=self.path) from None
        try:
            with self._open() as reader:
                indexed: dict[str, tuple[str, int]] | None = _topic_table(reader, self.path)
            index_error = None
        except LogFormatError as error:
            indexed, index_error = None, error
        held = layout.topic_counts()
        if indexed == held and layout.damage is None and layout.index_damage is None:
            return indexed
        if not layout.connections:
            if layout.damage is not None:
                raise LogFormatError(
                    f"cannot open the bag: {layout.damage.describe()}", path=self.path
                ) from None
            if index_error is not None:
                raise index_error
        self._layout = layout
        if indexed is None and layout.damage is not None and layout.damage.truncated:
            self.index_note = (
                f"the bag ends at byte {layout.damage.offset} of {layout.size}, before its "
                "index (a recording cut short); read by its chunks"
            )
        elif indexed is None:
            found = layout.index_damage or layout.damage
            if found is not None:
                reason = found.describe()
            else:
                reason = index_error.reason if index_error else "no index"
            self.index_note = (
                f"the bag cannot be read through its index ({reason}); read by its chunks"
            )
        else:
            changed = [
                f"{t}: {indexed.get(t, ('', 0))[1]} in the index, {n} in the chunks"
                for t, (_, n) in sorted(held.items())
                if indexed.get(t, ("", 0))[1] != n
            ]
            self.index_note = (
                f"the bag's index disagrees with its chunks ({'; '.join(changed) or 'damage'});"
                " read by its chunks, as rosbag reindex would"
            )
        table = dict(held)
        if layout.damage is not None:
            # damage hides messages: what the index lists beyond what was found is lost
            listed = layout.topic_counts(layout.index_counts) if layout.index_counts else {}
            most = layout.size // MIN_MESSAGE_BYTES  # a damaged count is no more than this
            for t, (msgtype, n) in (indexed or listed).items():
                table[t] = (msgtype, max(min(n, most), table.get(t, (msgtype, 0))[1]))
        return table

    @property
    def notes(self) -> list[str]:
        """The index note, if any (see ``index_note``)."""
        return [self.index_note] if self.index_note else []

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
                f"several LaserScan topics: {', '.join(candidates)}; choose one with --topic",
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

    @property
    def scans_in_file(self) -> int:
        return self.topics[self.topic][1]

    def info(self) -> dict[str, Any]:
        """Reader metadata plus the bag's topics and the scan count of the topic read (and,
        for a ROS 1 bag read by its chunks, ``index_note``: why)."""
        info = {
            **super().info(),
            "ros_version": self.ros_version,
            "topic": self.topic,
            "topics": {t: {"type": m, "messages": n} for t, (m, n) in sorted(self.topics.items())},
            "scans_in_file": self.scans_in_file,
        }
        if self.index_note:
            info["index_note"] = self.index_note
        return info

    def _scans(self) -> Iterator[tuple[int, Scan]]:
        if self._layout is not None:
            yield from self._scans_by_chunks()
            return
        with self._open() as reader:
            connections = [c for c in reader.connections if c.topic == self.topic]
            index = -1
            stream = self._guarded(reader, connections, lambda error: damages.append(error))
            damages: list[LogFormatError] = []
            times: Counter[int] = Counter()
            for index, (connection, bag_time, raw) in enumerate(stream):
                times[bag_time] += 1
                scan = self._decoded(reader.deserialize, raw, connection.msgtype, bag_time, index)
                if scan is None:
                    continue
                self.counts[self.topic] += 1
                yield index, scan
            if damages and self.ros_version == 1:  # skip mode: the rest by the chunks
                from scanlines.io.rosbag1 import walk

                layout = walk(self._paths[0], inside=True)
                yield from self._scans_by_chunks(layout, times, start=index + 1)
                return
            if damages:  # skip mode, and the index says what the damage cost
                (damage,) = damages
                self._bad_record(damage, count=self.topics[self.topic][1] - (index + 1))
            else:
                self._account_for_every_message(read=index + 1)
            for topic in self.topics:
                if topic != self.topic:
                    self.skipped[topic] = self.topics[topic][1]

    def _scans_by_chunks(
        self, layout: Any = None, seen: Counter[int] | None = None, start: int = 0
    ) -> Iterator[tuple[int, Scan]]:
        """A ROS 1 bag read by its chunks, in file order; damage is reported where it is,
        with what it cost. ``seen``: receive times of messages read already (through the
        index, before damage there), not read again; ``start``: how many those were."""
        from scanlines.io.rosbag1 import BagDamage, messages

        layout = self._layout if layout is None else layout
        seen = Counter() if seen is None else seen
        wanted = {c.id: c for c in layout.connections.values() if c.topic == self.topic}
        deserialize = self._ros1_deserializer(list(wanted.values()))
        index = start - 1
        damages: list[LogFormatError] = []
        for item in messages(self._paths[0], layout, set(wanted)):
            if isinstance(item, BagDamage):  # fail there, or count it at the end
                damages.append(self._damage_error(index + 1, item, layout))
                if self.on_error == "fail":
                    raise damages[0]
                continue
            if seen[item[1]] > 0:
                seen[item[1]] -= 1
                continue
            index += 1
            conn, bag_time, raw = item
            scan = self._decoded(deserialize, raw, wanted[conn].msgtype, bag_time, index)
            if scan is None:
                continue
            self.counts[self.topic] += 1
            yield index, scan
        read = index + 1
        if damages:
            msgtype, declared = self.topics[self.topic]
            missing = max(declared - read, len(damages))
            self._bad_record(damages[0], count=missing - len(damages) + 1)
            for error in damages[1:]:
                self._bad_record(error)
            self.topics[self.topic] = (msgtype, read + missing)
        else:
            self._account_for_every_message(read=read)
        for topic in self.topics:
            if topic != self.topic:
                self.skipped[topic] = self.topics[topic][1]

    def _damage_error(self, read: int, damage: Any, layout: Any) -> LogFormatError:
        """``damage`` (a :class:`~scanlines.io.rosbag1.BagDamage`), met after ``read``
        messages of the topic."""
        declared = self.topics[self.topic][1]
        held = layout.topic_counts().get(self.topic, ("", 0))[1]
        lost = (
            f"{declared - held} more that the index lists are lost"
            if declared > held
            else "the rest of the recording is lost"
            if damage.truncated
            else "what it hid is lost"
        )
        return LogFormatError(
            f"{damage.describe()}: {read} messages of {self.topic} read before it; {lost}",
            path=self.path,
            record=read + 1,
            unit="message",
        )

    def _ros1_deserializer(self, connections: list[Any]) -> Any:
        """``deserialize(raw, msgtype)`` for the topic's connections: the types of their
        message definitions (checked against their md5), else ROS 1 Noetic's."""
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        store = get_typestore(Stores.ROS1_NOETIC)
        try:
            types: dict[str, Any] = {}
            for connection in connections:
                if connection.msgdef.strip():
                    types.update(get_types_from_msg(connection.msgdef, connection.msgtype))
            if types:
                store = get_typestore(Stores.EMPTY)
                store.register(types)
            for connection in connections:
                have = store.generate_msgdef(connection.msgtype)[1]
                if connection.md5sum and have != connection.md5sum:
                    raise ValueError(
                        f"md5 {connection.md5sum} of {connection.msgtype} does not match "
                        f"its definition ({have})"
                    )
        except Exception as exc:  # rosbags raises several types on a bad definition
            raise LogFormatError(
                f"cannot read the message definition of {self.topic} ({describe(exc)})",
                path=self.path,
            ) from None
        return store.deserialize_ros1

    def _guarded(self, reader: Any, connections: list[Any], skipped: Any = None) -> Iterator[Any]:
        """The topic's messages, a storage error mid-stream turned into a LogFormatError:
        raised, or (skip mode, with ``skipped``, when the bag declares more messages than
        were read, so that the loss is counted) handed to ``skipped`` and the stream ended."""
        count = 0
        try:
            for item in reader.messages(connections):
                count += 1
                yield item
        except Exception as exc:  # rosbags raises several unrelated types here
            error = LogFormatError(
                f"the bag is damaged after message {count} of {self.topic} ({describe(exc)})",
                path=self.path,
                record=count + 1,
                unit="message",
            )
            if skipped is None or self.on_error != "skip" or self.topics[self.topic][1] <= count:
                raise error from None
            skipped(error)

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

    def _decoded(self, deserialize, raw, msgtype, bag_time, index):
        """Message ``index``'s scan, or ``None`` once a malformed or undecodable message
        is counted (or raised, in fail mode)."""
        try:
            return self._scan(deserialize(raw, msgtype), bag_time, index + 1)
        except LogFormatError as error:
            self._bad_record(error)
        except Exception as exc:  # a damaged message: any decoding error
            self._bad_record(
                LogFormatError(
                    f"cannot decode ({describe(exc)})",
                    path=self.path,
                    record=index + 1,
                    unit="message",
                )
            )
        return None

    def _scan(self, message: Any, bag_time: int, record: int) -> Scan:
        self._check_beams(len(message.ranges), record)
        try:
            return Scan.from_laserscan(message, fallback_time=bag_time * 1e-9)
        except ScanError as exc:
            field = str(exc).split(" ", 1)[0]
            raise LogFormatError(
                str(exc), path=self.path, record=record, field=field, unit="message"
            ) from None


def _topic_table(reader: Any, path: Path) -> dict[str, tuple[str, int]]:
    """Topic -> (message type, message count the bag declares). A count that is not a
    non-negative integer (a damaged ``metadata.yaml``) counts as 0: nothing is declared.

    A topic without a name or type (NULL in a damaged ``.db3``): a ``LaserScan`` one is an
    error (its scans cannot be told apart); another is listed as ``<topic N without a
    name>`` and skipped like any other topic."""
    table: dict[str, tuple[str, int]] = {}
    for connection in reader.connections:
        topic, msgtype = connection.topic, connection.msgtype
        if not isinstance(msgtype, str) or not msgtype:
            raise LogFormatError(
                f"topic {topic!r} of the bag has no message type (NULL or empty)",
                path=path,
                field="type",
            )
        if not isinstance(topic, str) or not topic:
            if msgtype in LASERSCAN_TYPES:
                raise LogFormatError(
                    f"a {msgtype} topic of the bag has no name ({topic!r}): the bag's "
                    "topic table is damaged",
                    path=path,
                    field="topic",
                )
            topic = f"<topic {connection.id} without a name>"
        msgtype, count = table.get(topic, (msgtype, 0))
        declared = connection.msgcount
        if isinstance(declared, bool) or not isinstance(declared, int) or declared < 0:
            declared = 0
        table[topic] = (msgtype, count + declared)
    return table
