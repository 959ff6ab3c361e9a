"""Which LaserScan sizes arrive over best-effort DDS on loopback, and how many of each.

    python tools/benchmarks/ros2_sizes.py [--beams 1000 10000 100000 1000000] [--count 20]
                                          [--rate 10] [--receive-buffer node|cyclone|SIZE]

For each size, a writer in this process publishes ``--count`` scans of that many beams at
``--rate`` Hz (ROS 2's default QoS, as ``scanlines ros2 --play``) to a reader in a process of
its own with the node's QoS (sensor data: best effort, keep last 5) that only takes them, so
what is measured is DDS, not extraction. Prints, per size, the scans that arrived and what the
reader's SAMPLE_LOST and SAMPLE_REJECTED statuses counted, and how many UDP datagrams the
kernel dropped meanwhile for a full socket receive buffer. ``--receive-buffer``: the socket
receive buffer both sides ask for (``Internal/SocketReceiveBufferSize max``; Linux grants at
most ``net.core.rmem_max``): ``node`` as ``scanlines ros2 --loopback`` (8 MB), ``cyclone``
Cyclone's default (1 MiB), or a size (``4MB``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from scanlines.ros2.dds import RECEIVE_BUFFER, loopback_config, ros_topic

#: Seconds the reader keeps taking after the writer's last scan.
LINGER = 3.0


def config(receive_buffer: str) -> str:
    """The loopback configuration asking for ``receive_buffer`` (``node``, ``cyclone``, a size)."""
    size = {"node": RECEIVE_BUFFER, "cyclone": None}.get(receive_buffer, receive_buffer)
    return loopback_config(size)


def receive_buffer_errors() -> int | None:
    """The kernel's count of UDP datagrams dropped for a full socket receive buffer
    (``RcvbufErrors`` in ``/proc/net/snmp``; machine-wide), or ``None`` off Linux."""
    try:
        table = Path("/proc/net/snmp").read_text().splitlines()
        rows = [line.split() for line in table if line.startswith("Udp:")]
    except OSError:
        return None
    return int(rows[1][rows[0].index("RcvbufErrors")])


def participant(domain_id: int, receive_buffer: str):
    from cyclonedds.domain import Domain, DomainParticipant

    domain = Domain(domain_id, config(receive_buffer))
    return domain, DomainParticipant(domain_id)


def receive(domain_id: int, receive_buffer: str, seconds: float) -> None:
    """The reader's process: take LaserScans for ``seconds``, then print the counts (JSON)."""
    from cyclonedds._clayer import ddspy_take
    from cyclonedds.core import InstanceState, SampleState, ViewState
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from scanlines.ros2 import messages as msg
    from scanlines.ros2.dds import prepare, sensor_data_qos

    prepare(msg.LaserScan)
    _, dp = participant(domain_id, receive_buffer)
    reader = DataReader(dp, Topic(dp, ros_topic("/scan"), msg.LaserScan), sensor_data_qos(5))
    print("ready", flush=True)
    mask = SampleState.Any | ViewState.Any | InstanceState.Any
    sizes: list[int] = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        for data, info in ddspy_take(reader._ref, mask, 5):
            if info.valid_data:
                sizes.append(len(data))
        time.sleep(0.001)
    lost = reader.get_sample_lost_status().total_count
    rejected = reader.get_sample_rejected_status().total_count
    print(json.dumps({"arrived": len(sizes), "lost": lost, "rejected": rejected}), flush=True)


def send(domain_id: int, beams: int, count: int, rate: float, receive_buffer: str) -> dict:
    """Publish ``count`` scans of ``beams`` beams to a fresh reader process; its counts."""
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from scanlines.ros2 import messages as msg
    from scanlines.ros2.dds import default_qos, prepare, wait_for_match

    prepare(msg.LaserScan)
    seconds = 5.0 + count / rate + LINGER
    reader = subprocess.Popen(
        [sys.executable, __file__, "--receive", str(seconds), "--domain-id", str(domain_id),
         "--receive-buffer", receive_buffer],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert reader.stdout is not None
        assert reader.stdout.readline().strip() == "ready"
        _, dp = participant(domain_id, receive_buffer)
        writer = DataWriter(dp, Topic(dp, ros_topic("/scan"), msg.LaserScan), default_qos())
        if not wait_for_match(writer, 30):
            sys.exit("the reader did not subscribe within 30 s")
        time.sleep(0.5)
        ranges = np.full(beams, 2.0, dtype=np.float32).tolist()
        step = 2 * np.pi / beams
        scan = msg.LaserScan(msg.Header(frame_id="laser"), -np.pi, -np.pi + (beams - 1) * step,
                             step, range_max=30.0, ranges=ranges)  # fmt: skip
        overflows = receive_buffer_errors()
        started = time.monotonic()
        for k in range(count):
            pause = started + k / rate - time.monotonic()
            if pause > 0:
                time.sleep(pause)
            scan.header.stamp = msg.Time(sec=k)
            writer.write(scan)
        counts = json.loads(reader.communicate(timeout=seconds + 60)[0].splitlines()[-1])
        after = receive_buffer_errors()
    finally:
        reader.kill()
    dropped = None if overflows is None or after is None else after - overflows
    return counts | {"beams": beams, "bytes": len(scan.serialize()), "sent": count,
                     "overflows": dropped}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--beams", type=int, nargs="+", default=[1000, 10000, 100000, 1000000])
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--rate", type=float, default=10.0)
    parser.add_argument("--domain-id", type=int, default=91)
    parser.add_argument("--receive-buffer", default="node")
    parser.add_argument("--receive", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.receive is not None:
        receive(args.domain_id, args.receive_buffer, args.receive)
        return
    print(f"{args.count} scans per size at {args.rate:g} Hz, receive buffer {args.receive_buffer}")
    for beams in args.beams:
        row = send(args.domain_id, beams, args.count, args.rate, args.receive_buffer)
        print(
            f"{row['beams']:>9,} beams ({row['bytes'] / 1e6:7.3f} MB): {row['arrived']:3d} of "
            f"{row['sent']} arrived; SAMPLE_LOST {row['lost']}, SAMPLE_REJECTED {row['rejected']}; "
            f"datagrams dropped by the kernel for a full receive buffer: {row['overflows']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
