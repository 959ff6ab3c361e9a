"""DDS domains for tests, each free on this machine and held by the process that took it.

Two clones of the repository running the test suite side by side on one machine must not
share a domain: a node of one would answer the other's subscribers. :func:`free_domain`
takes a domain no other process holds (a lock file per domain, ``fcntl.flock``, kept until
this process exits) whose Cyclone ports are free (nothing else, e.g. a fuzzing campaign or
a node started by hand, uses it), starting from a place that depends on the process id so
that concurrent sessions rarely try the same ones first.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import socket
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

#: The domains a test may take (ROS 2 allows 0 to 232; 0 is everyone's default).
DOMAINS = range(1, 233)
#: One folder of locks per user (another user's sessions are kept off by the port check).
LOCKS = Path(tempfile.gettempdir()) / f"scanlines-test-dds-domains-{os.getuid()}"
_held: dict[int, IO[bytes]] = {}


def cyclone_ports(domain: int) -> list[int]:
    """Cyclone's ports of ``domain`` (base 7400, domain gain 250): the discovery multicast
    port and the unicast discovery and data ports of the first participants."""
    base = 7400 + 250 * domain
    return [base, *range(base + 10, base + 22)]


def ports_free(domain: int) -> bool:
    """Whether no socket holds one of the domain's ports (a bind without reuse fails on a
    port in use)."""
    for port in cyclone_ports(domain):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            try:
                probe.bind(("0.0.0.0", port))
            except OSError:
                return False
    return True


def free_domain() -> int:
    """A domain no other process holds and no socket uses, held until this process exits."""
    LOCKS.mkdir(exist_ok=True)
    start = os.getpid() % len(DOMAINS)
    for k in range(len(DOMAINS)):
        domain = DOMAINS[(start + k) % len(DOMAINS)]
        if domain in _held:
            continue
        try:
            handle = (LOCKS / f"{domain}.lock").open("ab")
        except OSError:
            continue
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        if not ports_free(domain):
            handle.close()
            continue
        _held[domain] = handle
        return domain
    raise RuntimeError(f"no free DDS domain in {DOMAINS.start}..{DOMAINS.stop - 1}")


@contextlib.contextmanager
def domain_held() -> Iterator[int]:
    """:func:`free_domain` for a ``with`` block (the domain stays held until the process exits)."""
    yield free_domain()
