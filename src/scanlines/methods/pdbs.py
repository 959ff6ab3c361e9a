"""Point-distance-based segmentation (PDBS) followed by end-point-fit splitting.

The "PDBS algorithm" the paper compares against [1]_ (sec. 4.3, Fig. 12a and 13a):

1. cluster by the point-distance rule of Premebida and Nunes [2]_: consecutive
   returns ``P_{n-1}``, ``P_n`` are one cluster while
   ``|P_n - P_{n-1}| < C0 + C1 min(r_n, r_{n-1})`` with
   ``C1 = sqrt(2 (1 - cos(dalpha)))`` (``dalpha`` the angle between the two
   beams; ``C1 min(r)`` is the chord between the beams at the nearer range) and
   ``C0`` for the noise (``pdbs_c0``, 0.1 m here; ``breakpoints="pdbs"``) --
   :mod:`scanlines.steps.breakpoints`;
2. split every cluster at a fixed threshold, IEPF-style (Duda and Hart [3]_):
   at the point farthest from the chord between the cluster's end points, while
   that distance exceeds ``split_distance`` (0.1 m, as :mod:`~scanlines.methods.iepf`)
   -- ``split_at_farthest``;
3. total-least-squares line per part, parts with fewer than ``min_points`` (5)
   points or shorter than ``min_length`` (0 m) dropped;
4. corners between consecutive parts of one cluster by the shared rule of
   ``segment_events``; breakpoints from step 1.

It is :mod:`~scanlines.methods.iepf` with the PDBS clustering rule: the
threshold grows with range like the beam spacing on a surface facing the sensor
but, unlike the adaptive rules, not with the incidence angle, so walls seen at
grazing incidence are cut (the paper's under/over-segmentation, Fig. 12a).

References
----------
.. [1] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
.. [2] C. Premebida and U. Nunes, "Segmentation and geometric primitives
   extraction from 2D laser range data for mobile robot applications",
   Robotica 2005 (Actas do Encontro Cientifico), Coimbra, 2005.
.. [3] R. O. Duda and P. E. Hart, *Pattern Classification and Scene Analysis*,
   Wiley, 1973.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

from scanlines.methods.iepf import Iepf
from scanlines.params import Settings
from scanlines.steps.breakpoints import published_clustering


class Pdbs(Iepf):
    """IEPF with the PDBS clustering rule (module docstring)."""

    name = "pdbs"
    settings: ClassVar[Settings] = replace(
        Iepf.settings, clustering=published_clustering("pdbs", "PDBS: Premebida and Nunes")
    )
