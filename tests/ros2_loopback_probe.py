"""What ``scanlines ros2 --loopback`` lets through, measured between two network namespaces.

Run by ``test_ros2_loopback.py`` as ``unshare -n python ros2_loopback_probe.py DOMAIN``
(root): this process is the node's host, in a network namespace of its own; it makes a
second namespace (the "remote host") joined to it by a veth pair (``10.77.0.1`` here,
``10.77.0.2`` there), then:

1. starts ``scanlines ros2 --loopback`` here and ``scanlines ros2 --play --loopback`` here,
   and counts the RTPS frames that cross the veth (an ``AF_PACKET`` capture): what leaves;
2. from the remote namespace, sends one UDP datagram to each port the node holds open and
   counts (``/proc/net/snmp``) those the kernel delivered to a socket: what a remote host
   can reach;
3. from the remote namespace, plays the Intel excerpt to the node over DDS with Cyclone
   configured for the veth: whether a remote publisher gets scans into the node.

Prints one JSON line: ``frames`` (``rtps_out``, ``rtps_in``, ``icmp_out``... on the veth),
``node_ports``, ``datagrams_sent``, ``datagrams_delivered`` and ``datagrams_refused`` (to
the node's ports from the remote namespace), ``node_published`` (the local player plays 20
scans, the remote one 13) and the remote player's last line.
"""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

ETH_P_ALL = 0x0003
HERE, THERE = "10.77.0.1", "10.77.0.2"


def run(*words: str) -> None:
    subprocess.run(words, check=True, capture_output=True)


def remote_namespace() -> subprocess.Popen:
    """A process in a network namespace of its own, joined to this one by a veth pair."""
    remote = subprocess.Popen(["unshare", "-n", "sleep", "600"])
    time.sleep(0.5)
    run("ip", "link", "set", "lo", "up")
    run("ip", "link", "add", "veth0", "type", "veth", "peer", "name", "veth1", "netns",
        str(remote.pid))  # fmt: skip
    run("ip", "addr", "add", f"{HERE}/24", "dev", "veth0")
    run("ip", "link", "set", "veth0", "up")
    inside = ["nsenter", "-t", str(remote.pid), "-n"]
    run(*inside, "ip", "link", "set", "lo", "up")
    run(*inside, "ip", "addr", "add", f"{THERE}/24", "dev", "veth1")
    run(*inside, "ip", "link", "set", "veth1", "up")
    return remote


class Capture(threading.Thread):
    """The frames on ``veth0``, by direction: UDP datagrams that are RTPS messages, other
    UDP, ICMP (a port unreachable quotes the datagram it answers)."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
        self.sock.bind(("veth0", 0))
        self.sock.settimeout(0.2)
        self.counts: dict[str, int] = {}
        self.stop = False

    def run(self) -> None:
        while not self.stop:
            try:
                frame, address = self.sock.recvfrom(65535)
            except TimeoutError:
                continue
            except OSError:  # the veth went with the remote namespace
                return
            way = "out" if address[2] == socket.PACKET_OUTGOING else "in"
            kind = frame_kind(frame)
            self.counts[f"{kind}_{way}"] = self.counts.get(f"{kind}_{way}", 0) + 1


def frame_kind(frame: bytes) -> str:
    """``rtps``, ``udp``, ``icmp`` or ``other`` for an Ethernet frame."""
    if len(frame) < 34 or frame[12:14] != b"\x08\x00":  # IPv4 only (the veth has no IPv6)
        return "other"
    header = (frame[14] & 0x0F) * 4
    protocol = frame[23]
    if protocol == 1:
        return "icmp"
    if protocol != 17:
        return "other"
    payload = 14 + header + 8
    return "rtps" if frame[payload : payload + 4] == b"RTPS" else "udp"


def udp_counters() -> dict[str, int]:
    rows = [line.split() for line in Path("/proc/net/snmp").read_text().splitlines()]
    names, values = [r for r in rows if r[0] == "Udp:"][:2]
    return dict(zip(names[1:], map(int, values[1:]), strict=True))


def node_ports(pid: int) -> list[int]:
    """The UDP ports the node's process holds (``ss``)."""
    out = subprocess.run(["ss", "-uanpH"], capture_output=True, text=True, check=True).stdout
    return sorted({int(m) for line in out.splitlines() if f"pid={pid}," in line
                   for m in re.findall(r":(\d+)\s", line.split("users:")[0])[:1]})  # fmt: skip


def wait_for_ports(pid: int, count: int, timeout: float = 60.0) -> list[int]:
    """The node's ports once it holds ``count`` (Cyclone's three: discovery, data, sending)."""
    deadline = time.monotonic() + timeout
    ports = node_ports(pid)
    while len(ports) < count and time.monotonic() < deadline:
        time.sleep(0.5)
        ports = node_ports(pid)
    time.sleep(2.0)  # the node subscribes once its participant is up
    return node_ports(pid)


def published(stderr: str) -> int:
    found = re.search(r"(\d+) scans published", stderr)
    return int(found.group(1)) if found else -1


def scanlines(*words: str, env: dict | None = None, prefix: tuple = ()) -> subprocess.Popen:
    return subprocess.Popen(
        [*prefix, sys.executable, "-m", "scanlines", *words],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip


def main() -> None:
    domain, log = sys.argv[1], sys.argv[2]
    remote = remote_namespace()
    capture = Capture()
    capture.start()
    try:
        result = probe(domain, log, remote.pid)
    finally:
        remote.kill()
    capture.stop = True
    capture.join()
    result["frames"] = capture.counts
    print(json.dumps(result))


def probe(domain: str, log: str, remote: int) -> dict:
    inside = ("nsenter", "-t", str(remote), "-n")
    node = scanlines("ros2", "--loopback", "--domain-id", domain, "--duration", "90")
    ports = wait_for_ports(node.pid, 3)
    # 1. a local player: discovery and data on loopback
    local = scanlines("ros2", "--play", log, "--loopback", "--domain-id", domain, "--wait", "15",
                      "--rate", "50", "--scans", ":20")  # fmt: skip
    local.communicate(timeout=120)
    # 2. one datagram from the remote host to each of the node's ports
    before = udp_counters()
    sender = (
        "import socket,sys\n"
        "s=socket.socket(socket.AF_INET,socket.SOCK_DGRAM)\n"
        "m=b'RTPS\\x02\\x01\\x01\\x10'+bytes(12)\n"
        "[s.sendto(m,(sys.argv[1],int(p))) for p in sys.argv[2:]]\n"
    )
    run(*inside, sys.executable, "-c", sender, HERE, *map(str, ports))
    time.sleep(1.0)
    after = udp_counters()
    # 3. a remote player, Cyclone on the veth with the node's host as its peer
    config = (
        "<CycloneDDS><Domain id='any'><General><Interfaces><NetworkInterface "
        f"address='{THERE}'/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
        f"<Discovery><Peers><Peer address='{HERE}'/></Peers></Discovery></Domain></CycloneDDS>"
    )
    env = {**os.environ, "CYCLONEDDS_URI": config}
    far = scanlines("ros2", "--play", log, "--network", "--domain-id", domain, "--wait", "10",
                    "--rate", "50", "--scans", ":13", env=env, prefix=inside)  # fmt: skip
    _, far_err = far.communicate(timeout=120)
    node.terminate()
    _, node_err = node.communicate(timeout=60)
    local_published = published(node_err)
    return {
        "node_ports": ports,
        "datagrams_sent": len(ports),
        "datagrams_delivered": after["InDatagrams"] - before["InDatagrams"],
        "datagrams_refused": after["NoPorts"] - before["NoPorts"],
        "node_published": local_published,
        "remote_player": far_err.strip().splitlines()[-1:] if far_err else [],
    }


if __name__ == "__main__":
    main()
