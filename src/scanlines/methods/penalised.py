"""The penalised-likelihood objective that ``partition`` and ``surfaces`` minimise, declared once.

Both cut a scan's returns, in beam order, into runs that are line segments and single
returns left out as clutter, minimising

    sum over segments of  (chi2 / 2 + penalty)  +  clutter_cost x (returns left out)

(:mod:`~scanlines.methods.partition` describes the objective and its exact optimum,
:mod:`~scanlines.methods.surfaces` its weighing of returns). The kernels share one C++ unit,
``cpp/scanlines/methods/penalised.cpp``: the objective, its optimum, the outlier rounds, the
ring's second solve and the events read off the partition.
"""

from __future__ import annotations

from scanlines.methods.base import CompiledMethod
from scanlines.params import MAX_METRES, Param, number

__all__ = ["OBJECTIVE", "PenalisedMethod"]

OBJECTIVE: dict[str, Param] = {
    "penalty": Param(
        50.0, number(low=0.0, high=1e6), "cost of one more segment (nats of likelihood)"
    ),
    "clutter_cost": Param(
        20.0,
        number(low=0.0, low_open=True, high=1e6),
        "cost of leaving one return out as clutter (nats)",
    ),
    "model_error": Param(
        0.002,
        number(low=0.0, high=MAX_METRES),
        "how far real walls depart from a line (m), added to the range noise in quadrature",
    ),
}
"""The objective's parameters: the ``segments`` settings of every penalised method."""


class PenalisedMethod(CompiledMethod):
    """A method that minimises the penalised-likelihood objective (module docstring); its
    ``segments`` settings include :data:`OBJECTIVE`."""
