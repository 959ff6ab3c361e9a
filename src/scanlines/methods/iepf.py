"""Iterative end-point fit (IEPF): split clusters at the point farthest from their chord.

Algorithm (Duda and Hart [1]_, sec. 9.2; the recursive split of Pavlidis and
Horowitz [2]_; as compared by the paper [3]_, sec. 4.3-4.5):

1. cluster the returns by a fixed jump distance (``breakpoints="fixed"``,
   ``jump_distance = 0.3`` m) -- :mod:`scanlines.steps.breakpoints`;
2. in every cluster, find the point farthest from the chord between the
   cluster's first and last point (measured to the chord as a segment, so that
   a cluster closing on itself is first cut at its far corner); if that distance
   exceeds ``split_distance``,
   split there and repeat on both parts
   (``split_at_farthest``); the split point joins the part
   whose line it is nearer;
3. fit each part by total least squares (:mod:`scanlines.steps.fit`), drop parts
   with fewer than ``min_points`` points or shorter than ``min_length``;
4. corners where consecutive parts of one cluster meet (the shared rule of
   ``segment_events``); breakpoints from step 1.

Defaults: ``split_distance = 0.1`` m: with the 1-2 cm range noise of indoor
laser scanners it is 5 to 10 standard deviations, so noise alone rarely splits
a wall, yet a 90 deg corner is cut as soon as each side is longer than about
10 cm. ``min_points = 5``,
``min_length = 0``, ``range_sigma = 0.01`` m (covariances only).

There is no denoising and the threshold is fixed: at fine angular resolution the
farthest point of a noisy wall is a noise peak, and a threshold near the noise
cuts the wall there -- the over-segmentation the paper shows for IEPF (its
Fig. 10a).

The kernel is C++ (``cpp/scanlines/methods/split_methods.cpp``), shared with pdbs and
split_merge.

References
----------
.. [1] R. O. Duda and P. E. Hart, *Pattern Classification and Scene Analysis*,
   Wiley, 1973.
.. [2] T. Pavlidis and S. L. Horowitz, "Segmentation of plane curves", IEEE
   Trans. Computers C-23(8), 860-870, 1974.
.. [3] "An adaptive threshold line segment feature extraction algorithm for laser
   radar scanning environments", Electronics 11(11), 1759, 2022.
   doi:10.3390/electronics11111759
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from scanlines._core import iepf_stack
from scanlines.methods.base import CompiledMethod
from scanlines.params import Param, Settings, number
from scanlines.steps.assemble import output_settings
from scanlines.steps.breakpoints import published_clustering
from scanlines.steps.events import EVENTS
from scanlines.steps.split import REFERENCE_CODES


class SplitMethod(CompiledMethod):
    """A method that splits clusters at their farthest point (iepf, pdbs, split_merge): its
    ``segments`` record adds ``split_reference``, what the distance is measured from."""

    reference: ClassVar[str] = "chord"
    """A key of :data:`~scanlines.steps.split.REFERENCE_CODES`: ``"chord"`` or ``"line"``
    (the run's fitted line)."""

    @classmethod
    def record_of(cls, params: Mapping[str, Any]) -> dict[str, Any]:
        """The settings record of the parameters, and the method's ``split_reference``."""
        record = super().record_of(params)
        record["segments"]["split_reference"] = REFERENCE_CODES[cls.reference]
        return record


class Iepf(SplitMethod):
    """Iterative end-point fit (module docstring)."""

    name = "iepf"
    settings: ClassVar[Settings] = Settings(
        clustering=published_clustering("fixed", "IEPF: fixed jump distance"),
        segments={
            "split_distance": Param(
                0.1,
                number(low=0.0, low_open=True),
                "split where a point is this far from the chord (m)",
            ),
        },
        events=EVENTS,
        output=output_settings(5),
    )

    @staticmethod
    def kernel(*arguments):
        return iepf_stack(*arguments)
