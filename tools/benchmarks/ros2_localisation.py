"""The live localisation part of ros2_latency.py (``--map``): agreement with localize, latency."""

from __future__ import annotations

import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from scanlines.geometry.poses import compose, invert
from scanlines.io import open_log
from scanlines.map.localize import localize, read_line_map
from scanlines.ros2 import messages as msg
from scanlines.ros2.dds import default_qos, participant, ros_topic, take_serialized, wait_for_match
from scanlines.ros2.player import monotonic_stamps

#: Seconds the node may take to start.
START = 300.0


def reference(log: str, count: int, map_path: str, initial):
    """``localize`` on the first ``count`` scans: its run, the scans' restamped stamps, the
    log's mounting, the map's frame."""
    with open_log(log) as reader:
        scans = [scan for _, scan in zip(range(count), reader, strict=False)]
        mounting = reader.recorded_mounting or (0.0, 0.0, 0.0)
    lines, frame = read_line_map(map_path)
    started = time.perf_counter()
    run = localize(enumerate(scans), lines, frame, initial)
    seconds = time.perf_counter() - started
    stamps = monotonic_stamps([scan.timestamp for scan in scans])
    print(f"localize: {len(run.tracked)} scans in {seconds:.2f} s")
    return run, stamps, mounting, frame


def _writer(dp, topic, kind):
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    return DataWriter(dp, Topic(dp, ros_topic(topic), kind), default_qos())


def _reader(dp, topic, kind, depth=10_000):
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    return DataReader(dp, Topic(dp, ros_topic(topic), kind), default_qos(depth))


def initial_message(pose, stamp: float) -> msg.PoseWithCovarianceStamped:
    """``/initialpose`` at ``pose`` (map frame), ``localize``'s default prior."""
    from scanlines.map.filter import INITIAL_SIGMA

    x, y, theta = pose
    covariance = [0.0] * 36
    covariance[0] = covariance[7] = INITIAL_SIGMA[0] ** 2
    covariance[35] = INITIAL_SIGMA[1] ** 2
    sec, nanosec = divmod(round(stamp * 1e9), 1_000_000_000)
    return msg.PoseWithCovarianceStamped(
        header=msg.Header(stamp=msg.Time(sec, nanosec), frame_id="map"),
        pose=msg.PoseWithCovariance(
            pose=msg.Pose(msg.Point(x, y, 0.0),
                          msg.Quaternion(0.0, 0.0, math.sin(theta / 2), math.cos(theta / 2))),
            covariance=covariance,
        ),
    )  # fmt: skip


def collect(readers, expected: int, timeout: float) -> dict:
    """Samples (CDR bytes, source timestamp in ns) per reader until ``expected`` poses came
    and nothing more arrived for 5 s, or ``timeout`` seconds passed."""
    got = {name: [] for name in readers}
    deadline, last = time.monotonic() + timeout, time.monotonic()
    while time.monotonic() < deadline:
        more = False
        for name, reader in readers.items():
            for data, info in take_serialized(reader, 10_000):
                if info.valid_data:
                    got[name].append((bytes(data), info.source_timestamp))
                    more = True
        quiet = time.monotonic() - last
        if more:
            last = time.monotonic()
        elif quiet > 30 or (quiet > 5 and len(got["poses"]) >= expected):
            break
        time.sleep(0.005)
    return got


def _key(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _ns(seconds: float) -> int:
    sec, nanosec = divmod(round(seconds * 1e9), 1_000_000_000)
    return sec * 1_000_000_000 + nanosec


def compare(got: dict, run, stamps, mounting, frame) -> None:
    """Each amcl_pose against localize's pose of the scan of the same stamp; latencies."""
    by_stamp = {_ns(stamps[t.index]): t for t in run.tracked}
    scan_sent = {}
    for data, source in got["scans"]:
        scan_sent[_key(msg.LaserScan.deserialize(data).header.stamp)] = source
    errors, turns, latencies, unmatched = [], [], [], 0
    for data, source in got["poses"]:
        message = msg.PoseWithCovarianceStamped.deserialize(data)
        key = _key(message.header.stamp)
        want = by_stamp.get(key)
        if want is None:
            unmatched += 1
            continue
        base = compose(frame.world_pose(want.pose), invert(mounting))
        p, q = message.pose.pose.position, message.pose.pose.orientation
        errors.append(math.hypot(p.x - base[0], p.y - base[1]))
        turns.append(abs(math.remainder(2 * math.atan2(q.z, q.w) - base[2], math.tau)))
        if key in scan_sent:
            latencies.append((source - scan_sent[key]) * 1e-6)
    errors, turns = np.array(errors), np.degrees(turns)
    print(f"amcl_pose: {len(got['poses'])} received for {len(run.tracked)} scans localize "
          f"tracked ({unmatched} of stamps localize did not track)")  # fmt: skip
    if len(errors):
        print(f"distance to localize's pose: max {errors.max() * 1e3:.4f} mm, median "
              f"{np.median(errors) * 1e3:.4f} mm; within 1 cm: {(errors <= 0.01).sum()} of "
              f"{len(errors)}; heading max {turns.max():.5f} deg")  # fmt: skip
    if latencies:
        ms = np.array(latencies)
        print(f"latency player's scan write -> node's pose write: median {np.median(ms):.2f} "
              f"ms, p90 {np.percentile(ms, 90):.2f} ms, p99 {np.percentile(ms, 99):.2f} ms, "
              f"max {ms.max():.2f} ms ({len(ms)} scans)")  # fmt: skip


def localisation_benchmark(args) -> None:
    from scanlines.cli.localize import parse_initial_pose

    if not args.initial_pose:
        sys.exit("--map needs --initial-pose T,X,Y,YAW")
    initial = parse_initial_pose(args.initial_pose)
    run, stamps, mounting, frame = reference(args.log, args.scans, args.map, initial)
    first = run.tracked[0].index
    dp = participant(args.domain_id, loopback=True)
    readers = {
        "poses": _reader(dp, "/amcl_pose", msg.PoseWithCovarianceStamped),
        "scans": _reader(dp, "/scan", msg.LaserScan),
    }
    writer = _writer(dp, "/initialpose", msg.PoseWithCovarianceStamped)
    scanlines = [sys.executable, "-m", "scanlines", "ros2", "--loopback", "--domain-id",
                 str(args.domain_id)]  # fmt: skip
    node = subprocess.Popen(
        ["taskset", "-c", str(args.node_cpu), *scanlines, "--map", args.map, "--duration",
         str(args.scans / args.rate + 120), *args.node_arg],
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        if not wait_for_match(writer, START):
            sys.exit(f"the node did not subscribe to /initialpose within {START:g} s")
        time.sleep(1.0)
        base = compose(initial[1], invert(mounting))
        writer.write(initial_message(base, stamps[first]))
        writer.wait_for_acks(int(5e9))
        player = subprocess.run(
            [*scanlines, "--play", str(Path(args.log)), "--restamp", "--rate", str(args.rate),
             "--scans", f":{args.scans}", "--wait", "60"],
            stderr=subprocess.PIPE, text=True, timeout=args.scans / args.rate + 300,
        )  # fmt: skip
        got = collect(readers, len(run.tracked), 60)
        node.send_signal(2)
        _, err = node.communicate(timeout=60)
    finally:
        node.kill()
    print(f"{Path(args.log).name}: {args.scans} scans at {args.rate:g} Hz, node on core "
          f"{args.node_cpu}")  # fmt: skip
    print("\n".join(line for line in player.stderr.splitlines() if "step back" in line))
    print("\n".join(line for line in err.splitlines() if "localised" in line) or err[-3000:])
    compare(got, run, stamps, mounting, frame)
