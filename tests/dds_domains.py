"""DDS domain ids for tests that no other test run on this machine holds at the same time."""

from __future__ import annotations

import contextlib
import fcntl
import os
import random
import tempfile
from collections.abc import Iterator
from pathlib import Path

#: The ids handed out: above the fixed ids older tests use (61-90), within ROS 2's 0-232.
DOMAINS = range(150, 230)


@contextlib.contextmanager
def free_domain() -> Iterator[int]:
    """A domain id held (an exclusive lock on a file in the temporary directory) until the
    block ends: two test runs side by side, each with its workers, get different ids."""
    folder = Path(tempfile.gettempdir()) / "scanlines-dds-domains"
    folder.mkdir(exist_ok=True)
    order = list(DOMAINS)
    random.Random(os.getpid()).shuffle(order)
    for domain in order:
        handle = open(folder / f"{domain}.lock", "w")  # noqa: SIM115 (held past this loop)
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        try:
            yield domain
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
            handle.close()
        return
    raise RuntimeError(f"every DDS domain id in {DOMAINS} is held by another test")
