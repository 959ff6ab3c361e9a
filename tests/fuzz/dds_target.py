"""The DDS target: mutated ``sensor_msgs/LaserScan`` samples sent to one running ROS 2 node.

One ``scanlines ros2 --loopback`` process, on a private domain, takes every input in turn
(restarted only if it dies). Each input goes out from this process, a second Cyclone
participant on loopback:

* one that fits a UDP datagram, as a raw RTPS ``DATA`` submessage under the GUID of a real
  best-effort writer of this process (matched by the node, never written through), to the
  node's UDP ports (read in ``/proc``): its bytes arrive as they are, where Cyclone's own
  writer refuses to send CDR its check fails (truncated, a length past the end, no NUL);
* a larger one (a megabyte ``frame_id``) through a real writer, fragmented by Cyclone,
  which sends only what that check passes.

After each input the harness waits for its sign before sending the next (so no input is
overwritten on the node's keep-last-5 reader): a published ``LineSegmentList``, or one
line of the node's stderr. Every :data:`PROBE_EVERY` inputs, and after an input that left
no sign, a good scan must come back published.

Outcomes (channel ``dds node``)
-------------------------------
``success``
    The node published the scan's features.
``clean error``
    ``malformed scan`` or ``undecodable`` (the node's one line; counted), ``dropped by
    DDS`` (a warning of Cyclone's: it could not deserialise the sample, or the packet was
    malformed; the sample never reached the node),
    ``refused by the sender`` (too large for a datagram, and Cyclone's writer refused it),
    ``no sign`` (nothing, and the node then handled a good scan).
``defect``
    The node died (its last line), printed a traceback or any line it has no reason to
    print, counted a scan as failed, or stopped handling good scans.

At the end the node gets SIGTERM (channel ``node exit``, on the last input): exit 143, its
last line ``scanlines: terminated (...)``, whose malformed and undecodable counts are the
lines seen, no traceback. Given a :class:`~.binaries.BinaryWatch`, a node's death is
first checked against it (a shared object rewritten under the node kills it too).
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

from scanlines.ros2.dds import wait_for_match
from scanlines.ros2.player import SETTLE

from .binaries import BinaryWatch
from .channels import CLEAN_ERROR, DEFECT, SUCCESS, Case, Outcome, first_line

CHANNEL, EXIT_CHANNEL = "dds node", "node exit"
SEED_NAME = "laserscan-cdr"
DEFAULT_DOMAIN = 97
#: Largest input sent as one raw datagram (a UDP datagram holds 65,507 bytes).
MAX_DATAGRAM = 60_000
WAIT, WAIT_LARGE = 3.0, 10.0  # seconds for an input's sign (one datagram; fragmented)
PROBE_EVERY = 100
DYING = 10.0  # seconds a node that printed a traceback is given to exit
PROBE_WAIT = 30.0
START = 300.0  # seconds for the node to start (kernels from the cache, or compiled)
PROBE_SEC, PROBE_NANOSEC = 2_000_000_000, 123_456_789
RTPS_HEADER = b"RTPS\x02\x01\x01\x10"  # RTPS 2.1, vendor Eclipse Cyclone DDS
DATA, LITTLE_ENDIAN_WITH_DATA, ENTITYID_UNKNOWN = 0x15, 0x05, b"\x00\x00\x00\x00"

#: What a line of the node's stderr is (the first pattern that matches).
LINE_KINDS = (
    ("ready", re.compile(r"^scanlines ros2: .* listening on ")),
    ("malformed scan", re.compile(r"^scanlines ros2: skipped malformed scan \(.{0,400}$")),
    ("undecodable", re.compile(r"^scanlines ros2: skipped a sample that does not decode ")),
    ("failed", re.compile(r"^scanlines ros2: failed on a scan ")),
    # Cyclone's own warnings (a sample it could not deserialise, a malformed packet): the
    # input never reached the node
    ("dropped by DDS", re.compile(r"^\d+\.\d+ \[\d*\] +\S+: ")),
    ("stop", re.compile(r"^scanlines: (terminated|interrupted) \(")),
    ("notice", re.compile(r"^scanlines: compil")),
)
CLEAN_SIGNS = ("malformed scan", "undecodable", "dropped by DDS")
BAD_SIGNS = ("failed", "unexpected")


def line_kind(line: str) -> str:
    return next((kind for kind, pattern in LINE_KINDS if pattern.match(line)), "unexpected")


def udp_ports(pid: int) -> list[int]:
    """The UDP ports process ``pid`` has sockets on (Linux ``/proc``)."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    ports = []
    for table in ("/proc/net/udp", "/proc/net/udp6"):
        for row in Path(table).read_text().splitlines()[1:]:
            fields = row.split()
            if fields[9] in inodes:
                ports.append(int(fields[1].rsplit(":", 1)[1], 16))
    return sorted(set(ports))


class NodeProcess:
    """``scanlines ros2`` in a process of its own, its stderr read line by line."""

    def __init__(self, domain: int) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "scanlines", "ros2", "--loopback", "--domain-id", str(domain)],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            errors="replace",
        )
        self.lines: list[tuple[str, str]] = []
        self.counts: Counter[str] = Counter()
        self.lock = threading.Lock()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        for text in self.process.stderr:
            line = text.rstrip("\n")
            kind = line_kind(line)
            with self.lock:
                self.lines.append((kind, line))
                self.counts[kind] += 1

    def snapshot(self) -> Counter[str]:
        with self.lock:
            return Counter(self.counts)

    def new_lines(self, since: int) -> list[tuple[str, str]]:
        with self.lock:
            return self.lines[since:]

    def alive(self) -> bool:
        return self.process.poll() is None

    def wait_ready(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.alive():
            if self.snapshot()["ready"]:
                return True
            time.sleep(0.05)
        return False

    def last_words(self) -> str:
        with self.lock:
            lines = [line for _, line in self.lines if line.strip()]
        return lines[-1] if lines else "(nothing on stderr)"

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 60.0) -> int:
        if self.alive():
            self.process.send_signal(sig)
        try:
            code = self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = self.process.wait()
        self.reader.join(10)
        return code


class Sender:
    """This process's side: a writer for good scans and large inputs, a writer whose GUID
    raw datagrams carry, and a reader of the node's ``/line_segments``."""

    def __init__(self, domain: int) -> None:
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from scanlines.ros2 import messages as msg
        from scanlines.ros2.dds import default_qos, participant, ros_topic, sensor_data_qos

        dp = participant(domain, loopback=True)
        scans = Topic(dp, ros_topic("/scan"), msg.LaserScan)
        self.writer = DataWriter(dp, scans, sensor_data_qos())
        self.raw_writer = DataWriter(dp, scans, sensor_data_qos())
        guid = self.raw_writer.guid.bytes
        self.prefix, self.entity = guid[:12], guid[12:]
        self.sequence = 0
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.ports: list[int] = []
        segments = Topic(dp, ros_topic("/line_segments"), msg.LineSegmentList)
        self.published = DataReader(dp, segments, default_qos(depth=1000))

    def send(self, payload: bytes) -> str | None:
        """Send one input; why it could not be sent, or ``None``."""
        if len(payload) > MAX_DATAGRAM:
            from cyclonedds._clayer import ddspy_write

            code = ddspy_write(self.writer._ref, payload)
            return None if code == 0 else f"Cyclone's writer refused it (DDS error {code})"
        self.sequence += 1
        body = struct.pack("<HH", 0, 16) + ENTITYID_UNKNOWN + self.entity
        body += struct.pack("<iI", self.sequence >> 32, self.sequence & 0xFFFF_FFFF) + payload
        header = struct.pack("<BBH", DATA, LITTLE_ENDIAN_WITH_DATA, 0)  # 0: to the end
        datagram = RTPS_HEADER + self.prefix + header + body
        for port in self.ports:
            self.socket.sendto(datagram, ("127.0.0.1", port))
        return None

    def close(self) -> None:
        self.socket.close()


class Campaign:
    """One node, restarted when it dies, and the inputs sent to it one at a time."""

    def __init__(
        self, seed: bytes, domain: int = DEFAULT_DOMAIN, watch: BinaryWatch | None = None
    ) -> None:
        from scanlines.ros2 import messages as msg

        self.domain = domain
        self.watch = watch
        self.good = msg.LaserScan.deserialize(seed)
        self.sender = Sender(domain)
        self.node: NodeProcess | None = None
        self.published = 0  # outputs of inputs (not of probes) since the node started
        self.probes = self.answered = 0  # probes sent, the last one published

    # -- the node --------------------------------------------------------------------------

    def running(self) -> NodeProcess:
        if self.node is None or not self.node.alive():
            if self.node is not None:
                self.node.stop()
            self.node = NodeProcess(self.domain)
            self.published = 0
            if not self.node.wait_ready(START):
                raise RuntimeError(f"the node did not start: {self.node.last_words()}")
            self.sender.ports = udp_ports(self.node.process.pid)
            wait_for_match(self.sender.raw_writer, PROBE_WAIT)
            time.sleep(SETTLE)  # the node's side accepts the writers a moment later
            if not self.probe():
                raise RuntimeError("the node did not handle a good scan after starting")
        return self.node

    def collect(self) -> None:
        """Take the node's outputs: one with a probe's stamp counts as the probe's."""
        for message in self.sender.published.take(N=1000):
            if not hasattr(message, "header"):  # a writer's going (the node's end)
                continue
            stamp = message.header.stamp
            if stamp.sec > PROBE_SEC and stamp.nanosec == PROBE_NANOSEC:
                self.answered = max(self.answered, stamp.sec - PROBE_SEC)
            else:
                self.published += 1

    def probe(self) -> bool:
        """Whether a good scan, sent once a second, comes back published within
        :data:`PROBE_WAIT` seconds."""
        from scanlines.ros2 import messages as msg

        self.collect()
        self.probes += 1
        self.good.header.stamp = msg.Time(sec=PROBE_SEC + self.probes, nanosec=PROBE_NANOSEC)
        deadline, next_send = time.monotonic() + PROBE_WAIT, 0.0
        while time.monotonic() < deadline and self.node is not None and self.node.alive():
            if time.monotonic() >= next_send:
                self.sender.writer.write(self.good)
                next_send = time.monotonic() + 1.0
            self.collect()
            if self.answered == self.probes:
                return True
            time.sleep(0.002)
        return False

    # -- one input ---------------------------------------------------------------------------

    def run(self, payload: bytes) -> Outcome:
        node = self.running()
        counts, lines, published = node.snapshot(), len(node.lines), self.published
        refused = self.sender.send(payload)
        if refused is not None:
            return Outcome(CHANNEL, CLEAN_ERROR, "refused by the sender", refused)
        deadline = time.monotonic() + (WAIT if len(payload) <= MAX_DATAGRAM else WAIT_LARGE)
        signs: Counter[str] = Counter()
        while time.monotonic() < deadline and node.alive():
            self.collect()
            signs = node.snapshot() - counts
            signs["published"] = self.published - published
            if +signs:
                break
            time.sleep(0.001)
        return self.judge(node, +signs, node.new_lines(lines))

    def judge(self, node: NodeProcess, signs: Counter[str], lines: list) -> Outcome:
        bad = [line for kind, line in lines if kind in BAD_SIGNS]
        if bad and node.alive():  # a traceback: the death is this input's
            with contextlib.suppress(subprocess.TimeoutExpired):
                node.process.wait(DYING)
        if not node.alive():
            code = node.stop()
            self.check_binaries(f"the node died (exit {code})")
            return Outcome(CHANNEL, DEFECT, f"node died (exit {code})", node.last_words())
        if bad:
            return Outcome(CHANNEL, DEFECT, line_kind(bad[0]), first_line(bad[0]))
        if signs["published"]:
            return Outcome(CHANNEL, SUCCESS, "published")
        for kind in CLEAN_SIGNS:
            if signs[kind]:
                line = next(line for k, line in lines if k == kind)
                return Outcome(CHANNEL, CLEAN_ERROR, kind, first_line(line, 200))
        if self.probe():
            return Outcome(CHANNEL, CLEAN_ERROR, "no sign", "nothing; a good scan after it is")
        return Outcome(CHANNEL, DEFECT, "stopped handling scans", "no good scan published after")

    def check_alive(self) -> Outcome | None:
        """A defect if the node no longer publishes a good scan."""
        if self.node is not None and self.node.alive() and not self.probe():
            return Outcome(CHANNEL, DEFECT, "stopped handling scans", "a probe was not published")
        return None

    def check_binaries(self, when: str) -> None:
        if self.watch is not None:
            self.watch.check(when)

    # -- the end -------------------------------------------------------------------------------

    def close(self) -> Outcome:
        """SIGTERM to the node; the outcome of its exit."""
        node, self.node = self.node, None
        self.sender.close()
        if node is None:
            return Outcome(EXIT_CHANNEL, DEFECT, "no node", "the node was not running")
        if not node.alive():
            died = f"node died (exit {node.stop()})"
            self.check_binaries(f"the {died}")
            return Outcome(EXIT_CHANNEL, DEFECT, died, node.last_words())
        time.sleep(0.5)  # a probe sent twice is handled twice
        code = node.stop()
        lines = [line for _, line in node.lines]
        kinds = Counter(kind for kind, _ in node.lines)
        problem = exit_problem(code, lines, kinds)
        if problem:
            return Outcome(EXIT_CHANNEL, DEFECT, problem, first_line(lines[-1] if lines else ""))
        return Outcome(EXIT_CHANNEL, SUCCESS, "exit 143")


def exit_problem(code: int, lines: list[str], kinds: Counter[str]) -> str | None:
    """What is wrong with the node's exit on SIGTERM, or ``None``."""
    if code != 143:
        return f"exit {code} on SIGTERM"
    if any("Traceback" in line for line in lines):
        return "a traceback"
    if not lines or line_kind(lines[-1]) != "stop" or kinds["stop"] != 1:
        return "no one-line summary last"
    counts = re.search(r"(\d+) malformed skipped, (\d+) undecodable skipped", lines[-1])
    if counts is None:
        return "a summary without the counts"
    told = (int(counts[1]), int(counts[2]))
    if told != (kinds["malformed scan"], kinds["undecodable"]):
        return f"summary counts {told}, lines {kinds['malformed scan'], kinds['undecodable']}"
    return None


def run_dds(
    make: Callable[[int], tuple[str, bytes]],
    count: int,
    *,
    workdir: Path,
    seed: bytes,
    domain: int = DEFAULT_DOMAIN,
    progress: bool = False,
    watch: BinaryWatch | None = None,
) -> list[Case]:
    """Inputs ``make(0) ... make(count - 1)`` (each a plan name and the bytes) sent to one
    node; each input's bytes are kept in ``workdir/dds-inputs`` as ``.cdr`` files."""
    folder = workdir / "dds-inputs"
    folder.mkdir(parents=True, exist_ok=True)
    campaign = Campaign(seed, domain, watch)
    cases: list[Case] = []
    try:
        for index in range(count):
            plan, payload = make(index)
            path = folder / f"{index:05d}-laserscan.cdr"
            path.write_bytes(payload)
            case = Case(index, SEED_NAME, plan, path, [campaign.run(payload)])
            if (index + 1) % PROBE_EVERY == 0 and not case.defects:
                stopped = campaign.check_alive()
                case.outcomes += [stopped] if stopped else []
            cases.append(case)
            if progress and len(cases) % 100 == 0:
                print(f"  {len(cases)} of {count} DDS inputs", file=sys.stderr)
    finally:
        exited = campaign.close()
    if cases:
        cases[-1].outcomes.append(exited)
    return cases


COLUMNS = ("published", "malformed scan", "undecodable", "dropped by DDS", "refused by the sender",
           "no sign", DEFECT)  # fmt: skip


def outcomes_by_plan(cases: list[Case]) -> str:
    """The DDS inputs by mutator: what became of them (the node's exit on the last line)."""
    counts: dict[str, Counter[str]] = {}
    exits = []
    for case in cases:
        for outcome in case.outcomes:
            if outcome.channel == EXIT_CHANNEL:
                exits.append(outcome)
                continue
            column = DEFECT if outcome.kind == DEFECT else outcome.error
            counts.setdefault(case.plan, Counter())[column] += 1
            counts.setdefault("total", Counter())[column] += 1
    counts["total"] = counts.pop("total", Counter())
    width = max(len(name) for name in counts)
    rows = [["DDS samples to the node", *COLUMNS]]
    rows += [[name, *(str(c[column]) for column in COLUMNS)] for name, c in counts.items()]
    widths = [width] + [max(6, len(column)) for column in COLUMNS]
    lines = ["  ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)) for row in rows]
    lines += [f"node exit on SIGTERM: {o.kind} ({o.summary})" for o in exits]
    return "\n".join(line.rstrip() for line in lines)
