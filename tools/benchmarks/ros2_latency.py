"""Latency of the ROS 2 node, receipt to publish, per scan, at a fixed scan rate over DDS.

    python tools/benchmarks/ros2_latency.py [--rate 40] [--scans 400] [--log intel|sim1081]
        [--node-arg=--markers-topic= ...]
    python tools/benchmarks/ros2_latency.py --map MAP.json --log RAW.clf.gz
        --initial-pose T,X,Y,YAW [--scans 5505] [--rate 40] [--node-cpu 0]

With ``--map`` (live localisation): ``scanlines localize`` runs on the log's first
``--scans`` scans in this process; then the node (``scanlines ros2 --map``, pinned to core
``--node-cpu`` with ``taskset``) is given ``/initialpose`` (the pose of ``--initial-pose``
less the log's mounting, stamped with the restamped stamp of ``localize``'s first scan),
and ``scanlines ros2 --play LOG --restamp --rate R`` plays the scans into it. Printed: the
poses received, the largest distance of a scan's ``amcl_pose`` from ``localize``'s pose for
the same scan (matched by stamp), the node's own summary (latency from taking the scan off
its reader to writing its pose), and the latency from the player writing each scan to the
node writing its pose (DDS source timestamps, one clock).

Starts ``scanlines ros2`` (the default method, loopback DDS) in a process of its own,
publishes the scans to it at ``--rate`` Hz from this process, and prints the node's own
summary: scans published, and the median and 99th percentile of the time from taking
each scan off the DDS reader to its last message written. ``sim1081`` is a simulated
1,081-beam scanner (270 deg at 0.25 deg, 30 m: a Hokuyo UTM-30LX layout, the tim571's
noise) over random scenes; ``intel`` the shipped Intel excerpt (180 beams), cycled.
``--node-arg`` (repeatable) passes an option to the node: ``--node-arg=--markers-topic=``
turns its ``Marker`` off.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import math
import subprocess
import sys

from scanlines.ros2 import Player
from scanlines.ros2.dds import default_qos, participant, ros_topic, wait_for_match


def intel_scans(count: int) -> list:
    from scanlines.data import sample
    from scanlines.io import open_log

    with open_log(sample("intel")) as reader:
        scans = list(reader)
    return list(itertools.islice(itertools.cycle(scans), count))


def sim1081_scans(count: int) -> list:
    from scanlines.sim import get_sensor, random_scene

    spec = dataclasses.replace(get_sensor("tim571"), name="utm30lx_like", n_beams=1081,
                               angle_min=math.radians(-135.0),
                               angle_increment=math.radians(0.25), range_max=30.0)  # fmt: skip
    return [random_scene(seed=k % 50, sensor=spec).scan(seed=k).scan for k in range(count)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=40.0)
    parser.add_argument("--scans", type=int, default=400)
    parser.add_argument("--log", default="intel", help="intel, sim1081, or (--map) a log")
    parser.add_argument("--domain-id", type=int, default=90)
    parser.add_argument("--node-arg", action="append", default=[], help="an option of the node")
    parser.add_argument("--map", help="live localisation on this map (module docstring)")
    parser.add_argument("--initial-pose", help="--map: T,X,Y,YAW as localize takes it")
    parser.add_argument("--node-cpu", type=int, default=0, help="--map: the node's core")
    args = parser.parse_args()
    if args.map:
        from ros2_localisation import localisation_benchmark

        localisation_benchmark(args)
        return
    if args.log not in ("intel", "sim1081"):
        sys.exit("--log: intel or sim1081 (a log's path only with --map)")
    scans = (intel_scans if args.log == "intel" else sim1081_scans)(args.scans)
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from scanlines.ros2 import messages as msg

    dp = participant(args.domain_id, loopback=True)
    published = DataReader(dp, Topic(dp, ros_topic("/line_segments"), msg.LineSegmentList),
                           default_qos())  # fmt: skip
    node = subprocess.Popen(
        [sys.executable, "-m", "scanlines", "ros2", "--loopback", "--domain-id",
         str(args.domain_id), "--max-scans", str(len(scans)), "--duration", "600", *args.node_arg],
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        if not wait_for_match(published, 300):
            sys.exit("the node did not start within 300 s")
        player = Player(domain_id=args.domain_id, loopback=True)
        if not player.wait_for_subscriber(30):
            sys.exit("the node did not subscribe within 30 s")
        player.play(scans, rate=args.rate)
        _, err = node.communicate(timeout=60)
    finally:
        node.kill()
    beams = len(scans[0])
    summary = [line for line in err.splitlines() if "published" in line]
    print(f"{args.log}: {len(scans)} scans of {beams} beams at {args.rate:g} Hz")
    print("\n".join(summary) or err)


if __name__ == "__main__":
    main()
