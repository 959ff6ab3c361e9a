"""Line segments as the exact penalised-likelihood partition of a scan's returns.

The method solves one problem per scan: cut the returns, in beam order, into runs that are
line segments and single returns left out as clutter, so that the total cost

    sum over segments of  (chi2 / 2 + penalty)  +  clutter_cost x (returns left out)

is smallest. A segment's ``chi2`` is its weighted residual along the beams: the depth of
its returns along their mean bearing regressed on their lateral position (range noise moves
a return along its beam, so a short piece of a wall sampled denser than its noise cannot
turn its line towards the beams to explain the noise), the model error, which lies across
the wall, growing along the beams with the segment's slope. Each return ``p`` weighs
``1 / (sigma(r_p)^2 + model_error^2)``, with ``sigma(r)`` the range noise measured from the
data (the sensor profile's noise line, else the scan's own, :mod:`scanlines.steps.noise`)
and ``model_error`` the flatness of real walls. The lines reported are the total-least-squares
lines of each segment's returns. The costs are
negative log-likelihoods in nats, so ``penalty`` and ``clutter_cost`` are nats too: a segment
is cut where the fit improves by more than the price of one more segment, a return is left
out where its residual costs more than ``clutter_cost`` (about ``sqrt(2 clutter_cost)``
sigmas). Runs of two or more missing beams end a cluster, and no segment spans them.

The optimum is found exactly by dynamic programming over the positions, with every
segment's cost in O(1) from prefix sums of the weighted moments, and pruned as PELT [1]_
does: a start ``s`` whose best cost to ``t`` already exceeds the best cost of ``t`` itself
can never start the last segment of a later optimum (a segment's chi2 only grows when it
is cut in two), so it is dropped once every later segment from ``t`` would be long enough.

Events are read off the partition. Between two neighbouring pieces (segments or left-out
returns) of one cluster a *breakpoint* is reported at the last return of the first piece
when the two facing returns are farther apart than a surface seen at up to 80 deg of
incidence can put them (Borges and Aldon's bound [2]_) plus three sigmas of their
difference. Two neighbouring segments meet at a *corner* when their lines turn by more
than three standard deviations of the turn (the direction variance of a weighted fit is
``1 / lambda_max`` of its scatter) and intersect within the facing returns' spacing plus
three noise sigmas of both facing returns; the corner is the facing return nearer the
intersection.

With ``max_rho_sigma`` (preset ``"repeatable"``) only well-determined lines are kept:
segments whose ``rho`` standard deviation, in the covariance reported with them, exceeds
the bound are dropped, which removes lines through sparse returns at grazing incidence and
short lines far from the foot of their normal.

The kernel is C++ (``cpp/scanlines/methods/partition.cpp``): one call per stack of scans,
without the GIL. Its fixed bounds: events at ``EVENT_SIGMAS = 3`` standard deviations;
neighbouring returns cut apart beyond the surface bound plus ``CUT_SIGMAS = 5`` sigmas of
their difference (Gaussian noise crosses it once in about 1.7 million pairs); the surface
bound's grazing angle ``10 deg`` (80 deg of incidence); the last segment reaches back over
at most ``LOOK_BACK = 256`` returns (a longer wall is cut there and joined again on the same
objective); at most ``3`` rounds of partition and outlier choice.

References
----------
.. [1] R. Killick, P. Fearnhead and I. A. Eckley, "Optimal detection of changepoints with
   a linear computational cost", J. American Statistical Association 107, 1590-1598, 2012.
.. [2] G. A. Borges and M.-J. Aldon, "Line extraction in 2D range images for mobile
   robotics", J. Intelligent and Robotic Systems 40, 267-297, 2004.
"""

from __future__ import annotations

from typing import Any, ClassVar

from scanlines._core import partition_stack
from scanlines.methods.penalised import OBJECTIVE, PenalisedMethod
from scanlines.params import MAX_METRES, Param, Settings, auto_or, number, optional
from scanlines.steps.assemble import output_settings

__all__ = ["Partition"]


class Partition(PenalisedMethod):
    """The penalised-likelihood partition of each scan into line segments (module
    docstring)."""

    name = "partition"
    settings: ClassVar[Settings] = Settings(
        noise={
            "noise_sigma": Param(
                "auto",
                auto_or(number(low=0.0, low_open=True, high=MAX_METRES)),
                "range noise (m), or auto: the sensor profile's noise line, else the scan's own",
            ),
        },
        segments=OBJECTIVE,
        output={
            **output_settings(4),
            "max_rho_sigma": Param(
                None,
                optional(number(low=0.0, low_open=True, high=MAX_METRES)),
                "keep only segments whose rho standard deviation is at most this (m), or None: all",
            ),
        },
    )
    presets: ClassVar[dict[str, dict[str, Any]]] = {"repeatable": {"max_rho_sigma": 0.02}}

    @staticmethod
    def kernel(*arguments):
        return partition_stack(*arguments)
