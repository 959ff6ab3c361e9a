"""Fixtures of the log reader/writer tests."""

from __future__ import annotations

from pathlib import Path

import pytest
from io_helpers import FIXTURES


@pytest.fixture
def fixtures() -> Path:
    """The directory of the committed test files."""
    return FIXTURES
