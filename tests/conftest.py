import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))


def pytest_addoption(parser):
    parser.addoption(
        "--long",
        action="store_true",
        default=False,
        help="run the long versions of the fuzzing and signal tests",
    )


@pytest.fixture
def dds_domain() -> int:
    """A DDS domain no other process on this machine holds or uses (``dds_domains.py``)."""
    from dds_domains import free_domain

    return free_domain()
