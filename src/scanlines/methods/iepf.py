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
   (:func:`scanlines.steps.split.split_at_farthest`); the split point joins the part
   whose line it is nearer;
3. fit each part by total least squares (:mod:`scanlines.steps.fit`), drop parts
   with fewer than ``min_points`` points or shorter than ``min_length``;
4. corners where consecutive parts of one cluster meet (the shared rule of
   :func:`scanlines.steps.events.segment_events`); breakpoints from step 1.

Defaults: ``split_distance = 0.1`` m: with the 1-2 cm range noise of indoor
laser scanners it is 5 to 10 standard deviations, so noise alone rarely splits
a wall, yet a 90 deg corner is cut as soon as each side is longer than about
10 cm. ``min_points = 5``,
``min_length = 0``, ``range_sigma = 0.01`` m (covariances only).

There is no denoising and the threshold is fixed: at fine angular resolution the
farthest point of a noisy wall is a noise peak, and a threshold near the noise
cuts the wall there -- the over-segmentation the paper shows for IEPF (its
Fig. 10a).

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

import numpy as np

from scanlines._jit import kernel, scan_kernel
from scanlines.methods.base import CompiledMethod, as_record, cluster_scan, kernel_tuple
from scanlines.params import Param, number, segment_params, with_default
from scanlines.steps.assemble import Output, empty_result, finish
from scanlines.steps.breakpoints import BREAKPOINT_PARAMS, LITERAL_CLUSTERING, RuleSpec
from scanlines.steps.events import EVENT_PARAMS
from scanlines.steps.fit import prefix_moments
from scanlines.steps.returns import valid_returns
from scanlines.steps.split import REFERENCE_CODES, split_at_farthest
from scanlines.steps.stack import add_row, new_table


class SplitMethod(CompiledMethod):
    """A method that splits clusters at their farthest point (iepf, pdbs, split_merge): its
    settings record adds ``split_reference``, what the distance is measured from, and its
    kernel takes the clustering rule and the output bounds as their tuples."""

    reference: ClassVar[str] = "chord"
    """A key of :data:`~scanlines.steps.split.REFERENCE_CODES`: ``"chord"`` or ``"fit"``."""

    @classmethod
    def settings_of(cls, params: Mapping[str, Any]) -> dict[str, np.generic]:
        """The settings the parameters declare, and the method's ``split_reference``."""
        reference = np.int64(REFERENCE_CODES[cls.reference])
        return {**super().settings_of(params), "split_reference": reference}

    def kernel_arguments(self) -> tuple[Any, ...]:
        """The settings record, the :class:`~scanlines.steps.breakpoints.RuleSpec` and the
        :class:`~scanlines.steps.assemble.Output`."""
        rule = kernel_tuple(RuleSpec, self.parameters, self.params)
        return as_record(self.settings), rule, kernel_tuple(Output, self.parameters, self.params)


class Iepf(SplitMethod):
    """Iterative end-point fit (module docstring)."""

    name = "iepf"
    parameters: ClassVar[dict[str, Param]] = {
        **segment_params(5),
        **BREAKPOINT_PARAMS,
        **LITERAL_CLUSTERING,
        "breakpoints": with_default(
            BREAKPOINT_PARAMS["breakpoints"], "fixed", "IEPF: fixed jump distance"
        ),
        "split_distance": Param(
            0.1,
            number(low=0.0, low_open=True),
            "split where a point is this far from the chord (m)",
        ),
        **EVENT_PARAMS,
    }

    @staticmethod
    def kernel(*arguments):
        return iepf_stack(*arguments)


@kernel
def iepf_stack(stack, valid, cos, sin, step, full_circle, angle_min, noise, settings, rule, out):
    """:func:`iepf_scan` of each row of ``stack``, as one flat table."""
    table = new_table(stack.shape[0])
    for row in range(stack.shape[0]):
        result = iepf_scan(
            stack[row], valid[row], cos, sin, step, full_circle, angle_min, noise, settings,
            rule, out,
        )  # fmt: skip
        table = add_row(table, row, result)
    return table


@scan_kernel
def iepf_scan(ranges, valid, cos, sin, step, full_circle, angle_min, noise, settings, rule, out):
    """The whole method on one scan: the result arrays (see :class:`CompiledMethod`)."""
    s = settings[0]
    n_beams = ranges.shape[0]
    none = np.zeros(0, dtype=np.int64)
    returns = valid_returns(ranges, valid, cos, sin)
    if returns.index.shape[0] == 0:
        return empty_result(none, none)
    returns, moments, runs, clusters = cluster_and_split(
        returns, n_beams, step, full_circle, rule, (s.split_distance, s.split_reference), noise
    )
    return finish(
        returns, n_beams, full_circle, moments, runs, clusters, none, angle_min, out, noise
    )


@kernel
def cluster_and_split(returns, n_beams, step, full_circle, rule, split, noise):
    """Steps 1-2 of the split methods: cluster by the rule (a
    :class:`~scanlines.steps.breakpoints.RuleSpec`), split every cluster at the point
    farthest from its chord (or line) while it is farther than ``split_distance``
    (``split``: ``(split_distance, split_reference)``, not the record: the methods' records
    differ, and one compiled kernel serves them all).

    Returns the (possibly rotated) returns, their moments, the runs ``(a, b, group)`` and
    the clustering ``(True, ring, breakpoints)`` as :func:`~scanlines.steps.assemble.finish`
    takes them.
    """
    returns, start, end, breakpoints, ring = cluster_scan(
        returns, n_beams, step, full_circle, rule, noise
    )
    moments = prefix_moments(returns.x, returns.y)
    clusters = np.arange(start.shape[0])
    distance, reference = split
    a, b, group = split_at_farthest(
        returns.x, returns.y, moments, start, end, clusters, distance, reference
    )
    return returns, moments, (a, b, group), (np.bool_(True), ring, breakpoints)
