"""The settings of global localisation: read by map/relocalise.py and map/localize.py."""

from __future__ import annotations

import math
from typing import ClassVar

from scanlines.params import MAX_COUNT, MAX_METRES, MAX_SCANS, Param, integer, number
from scanlines.params.tables import Groups, SettingsTable

__all__ = ["SearchSettings"]

_METRES = number(low=0.0, high=MAX_METRES)
_SHARE = number(low=0.0, high=1.0)
_SCANS = integer(1, MAX_SCANS)


class SearchSettings(SettingsTable):
    """The constants of global localisation (metres, radians, shares of returns, scans)."""

    groups: ClassVar[Groups] = {
        "score": {
            "near": Param(
                0.05,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "a return within this of a map line is explained (m)",
            ),
            "cell": Param(
                0.025,
                number(low=0.001, high=MAX_METRES),
                "cell of the bitmap of the places near a map line (m)",
            ),
            "score_points": Param(
                60, integer(1, MAX_COUNT), "returns scored per scan (evenly subsampled)"
            ),
        },
        "candidates": {
            "segments": Param(
                4, integer(2, MAX_COUNT), "the scan's longest segments paired into candidates"
            ),
            "min_segment": Param(0.6, _METRES, "shorter segments are not paired (m)"),
            "min_line": Param(0.5, _METRES, "shorter map lines are not paired (m)"),
            "max_pair_distance": Param(
                8.0, _METRES, "two map lines farther apart than this are not a pair (m)"
            ),
            "min_crossing": Param(
                math.radians(30.0),
                number(low=0.0, high=math.pi / 2),
                "two lines pair when they cross at this angle or more (rad)",
            ),
            "angle_tolerance": Param(
                math.radians(3.0),
                number(low=0.0, high=math.pi / 2),
                "a segment pair's angle matches a line pair's within this (rad)",
            ),
            "overlap_slack": Param(
                0.3, _METRES, "a segment may overhang its map line's ends by this (m)"
            ),
            "end_tolerance": Param(
                0.15,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "a segment's real end matches a map line's end point this far off its line (m)",
            ),
            "end_candidates": Param(
                2,
                integer(0, MAX_COUNT),
                "best distinct candidates from a segment's end made hypotheses where no two "
                "segments cross and no hypothesis explains found_share (0: none)",
            ),
            "candidates": Param(
                20, integer(1, MAX_COUNT), "best distinct candidates of a scan made hypotheses"
            ),
            "distinct_distance": Param(
                0.5, _METRES, "poses nearer than this and distinct_angle are one (m)"
            ),
            "distinct_angle": Param(
                math.radians(10.0),
                number(low=0.0, high=math.pi),
                "poses nearer than this and distinct_distance are one (rad)",
            ),
        },
        "hypotheses": {
            "max_hypotheses": Param(
                40, integer(1, MAX_COUNT), "most hypotheses kept (the best of recent scans)"
            ),
            "sigma_xy": Param(
                0.1,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "a new hypothesis's position sigma (m)",
            ),
            "sigma_theta": Param(
                math.radians(3.0),
                number(low=0.0, low_open=True, high=math.pi),
                "a new hypothesis's heading sigma (rad)",
            ),
            "refine_every": Param(
                2, _SCANS, "hypotheses are stepped through their filter every this many scans"
            ),
            "refine_every_tracked": Param(
                10, _SCANS, "refine_every while the filter still has a pose of its own"
            ),
            "drop_share": Param(
                0.25,
                _SHARE,
                "a hypothesis explaining less over drop_after scans (a candidate, on its scan) "
                "is dropped",
            ),
            "drop_after": Param(5, _SCANS, "scans a hypothesis is scored over to be dropped"),
        },
        "winner": {
            "agree": Param(
                10, _SCANS, "scans a hypothesis near the filter's pose must explain found_share"
            ),
            "found_share": Param(
                0.6, _SHARE, "share of returns a near hypothesis explains over agree scans"
            ),
            "agree_far": Param(
                20, _SCANS, "scans a hypothesis far from the filter's pose must explain over"
            ),
            "found_share_far": Param(
                0.6, _SHARE, "share of returns a far hypothesis explains over agree_far scans"
            ),
            "near_distance": Param(
                1.0,
                _METRES,
                "a hypothesis this near the filter's pose, or near_sigmas of its sigma, is near "
                "(m)",
            ),
            "near_angle": Param(
                math.radians(15.0),
                number(low=0.0, high=math.pi),
                "a hypothesis turned this little, or near_sigmas of the sigma, is near (rad)",
            ),
            "near_sigmas": Param(3.0, number(low=0.0), "the filter's sigmas that count as near"),
            "margin": Param(
                0.1, _SHARE, "the winner's share exceeds every distinct rival's by this"
            ),
            "clearance": Param(
                0.3,
                _METRES,
                "a beam passing a map line more than this short of its return sees through it (m)",
            ),
            "reach": Param(
                10.0,
                number(low=0.0, low_open=True, high=MAX_METRES),
                "beams are checked for crossing a map line up to this far (m)",
            ),
            "max_crossed": Param(
                0.2, _SHARE, "a winner seeing more of its returns through a map line is refused"
            ),
            "checks": Param(3, _SCANS, "scans of that check before a winner is taken"),
            "mapped_share": Param(
                0.35,
                _SHARE,
                "a hypothesis explaining less over agree_far scans is not judged where the map "
                "has lines",
            ),
            "mapped_fraction": Param(
                0.7,
                _SHARE,
                "share of the returns whose beams meet a map line a hypothesis explains to be "
                "taken over agree_far scans (below found_share_far of all)",
            ),
            "max_through": Param(
                0.03,
                _SHARE,
                "most returns seen through a map line (beams cast on the map's lines) such a "
                "hypothesis may have",
            ),
        },
        "lost": {
            "lost_share": Param(0.25, _SHARE, "a scan explaining a smaller share is low"),
            "lost_after": Param(
                10, _SCANS, "the filter is lost after this many low scans in a row"
            ),
            "propose_every": Param(
                5, _SCANS, "new hypotheses every this many scans while lost without a pose"
            ),
            "propose_every_tracked": Param(
                10, _SCANS, "propose_every while the filter still has a pose of its own"
            ),
            "propose_later": Param(
                50, _SCANS, "propose_every_tracked after patient scans of search"
            ),
            "patient": Param(
                30, integer(0, MAX_SCANS), "scans of search before proposing at propose_later"
            ),
        },
    }
