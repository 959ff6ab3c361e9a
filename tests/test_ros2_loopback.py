"""What ``scanlines ros2 --loopback`` keeps in and lets in, measured between two network
namespaces joined by a veth pair (``ros2_loopback_probe.py``; needs root, ``unshare``,
``nsenter``, ``ip`` and ``ss``): no DDS message leaves on the other interface and a remote
publisher gets no scan into the node; but Cyclone binds the node's discovery and data
ports to every interface (eclipse-cyclonedds #1923, #2090), so a remote host's datagrams
to them are delivered, as the README says."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("cyclonedds")

from scanlines.data import sample

pytestmark = pytest.mark.slow  # three DDS processes in two network namespaces, 40 s

PROBE = Path(__file__).with_name("ros2_loopback_probe.py")
#: Any domain: the namespaces are private, no other test can share it.
DOMAIN = 77


def namespaces_available() -> bool:
    if os.geteuid() != 0 or not all(map(shutil.which, ("unshare", "nsenter", "ip", "ss"))):
        return False
    tried = subprocess.run(
        ["unshare", "-n", "ip", "link", "add", "v0", "type", "veth", "peer", "name", "v1"],
        capture_output=True,
        check=False,
    )
    return tried.returncode == 0


@pytest.fixture(scope="module")
def probe() -> dict:
    if not namespaces_available():
        pytest.skip("needs root and network namespaces (unshare -n) with veth pairs")
    done = subprocess.run(
        ["unshare", "-n", sys.executable, str(PROBE), str(DOMAIN), str(sample("intel"))],
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_no_dds_message_leaves_on_another_interface(probe):
    assert probe["frames"].get("rtps_in", 0) > 0  # the remote player did try
    assert probe["frames"].get("rtps_out", 0) == 0, probe


def test_a_remote_publisher_gets_no_scan_into_the_node(probe):
    assert probe["remote_player"][0].startswith("scanlines ros2: published 13 scans"), probe
    assert probe["node_published"] == 20, probe  # the local player's 20, none of the 13


def test_a_remote_host_reaches_the_ports_cyclone_binds_to_every_interface(probe):
    """The two ports bound to 0.0.0.0 (discovery, 7410 + 250 x domain, and data, 7411 +
    250 x domain, for the first participant) take a remote datagram; the one bound to
    127.0.0.1 does not. If Cyclone ever binds them to 127.0.0.1, the README's account of
    ``--loopback`` must change."""
    base = 7400 + 250 * DOMAIN
    assert {base + 10, base + 11} <= set(probe["node_ports"]), probe
    assert probe["datagrams_delivered"] == 2, probe
    assert probe["datagrams_refused"] == probe["datagrams_sent"] - 2, probe
