"""The ROS 2 node's one-line summary and the text it quotes from the wire."""

import pytest

pytest.importorskip("cyclonedds")

from scanlines.ros2.node import NodeStats, clip


def test_the_summary_counts_every_kind_of_sample():
    stats = NodeStats(published=7, skipped=2, undecodable=3)
    assert stats.summary() == "7 scans published, 2 malformed skipped, 3 undecodable skipped"
    stats.failed, stats.dds_lost, stats.dds_rejected = 1, 4, 5
    assert stats.summary() == (
        "7 scans published, 2 malformed skipped, 3 undecodable skipped, 1 failed, "
        "DDS reported 4 lost and 5 rejected"
    )


def test_a_long_frame_id_is_quoted_short_and_on_one_line():
    assert clip("laser") == "'laser'"
    text = "a\nb" * 400_000
    quoted = clip(text)
    assert quoted == repr(text[:80]) + "... (1,200,000 chars)"
    assert "\n" not in quoted
    assert len(quoted) < 4 * 80 + 30  # 80 characters, each at most 4 once escaped
