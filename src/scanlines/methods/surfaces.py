"""Line segments of the surfaces a scan sees, found by one penalised-likelihood objective.

The method cuts the returns, in beam order, into runs that are line segments and single
returns left out as clutter, minimising :mod:`~scanlines.methods.partition`'s cost

    sum over segments of  (chi2 / 2 + penalty)  +  clutter_cost x (returns left out)

exactly (dynamic programming with PELT pruning), a segment's chi2 measured along the beams
as there, with these changes:

* **A return weighs its footprint.** Each return counts ``min(1, r x increment /
  footprint)`` observations in the chi2 (leaving a return out costs the same for each): the
  errors of a finely sampled wall (millimetres of waviness, the beam's spot) are correlated
  along it, and counting thousands of returns as independent would turn that waviness into cuts
  (at least 0.1: ten returns count as one observation at the finest sampling).
* **A lone spike does not cut a surface.** A return off the surface its two neighbours
  share opens no new cluster, and a run may span a left-out return at the clutter cost.
* **Events mark where surfaces end.** Breakpoints and corners are read between the held
  returns of neighbouring segments, so a spike or a mixed pixel left out inside a wall is
  no event; a breakpoint where the facing returns are farther apart than a surface seen at
  up to 80 deg of incidence can put them (plus three sigmas), a corner where the two lines
  turn by more than three standard deviations and meet between the facing returns.

And one output rule: **pieces of one surface share one line.** A segment and one of the
three segments before it (with returns of something else or missing beams between them, as
a wall behind a chair leg), whose returns one line explains for less than the price of a
segment (``penalty``), are reported each with that common line, its covariance and its
rms, fitted to the returns of all of them.

Weights are ``footprint / (sigma(r)^2 + model_error^2)`` with ``sigma(r)`` the measured
range noise: a sensor profile's noise line, else the scan's own (:mod:`scanlines.steps.noise`);
an :class:`~scanlines.Extractor` without a profile learns the line from the first scans it
extracts. ``two_stage=True`` searches the optimum in two stages: the same objective at a quarter of
the penalty on blocks of four returns (cut also where clusters open) proposes boundaries,
then the search over every return lets a segment longer than a few returns start only
within 16 returns of one of them. It found the full search's partition on 893 of 900 scans
of six shared real logs and on 748 of the 750 shipped scans, and is about four times faster at
10,000 beams (docs/decisions/surfaces.md); it is off by default.

The kernel is C++ (``cpp/scanlines/methods/surfaces.cpp``, the objective shared
with ``partition`` in ``penalised.cpp``): one call per stack of scans, without the GIL.
"""

from __future__ import annotations

from typing import Any, ClassVar

from scanlines._core import surfaces_stack
from scanlines.methods.penalised import OBJECTIVE, PenalisedMethod
from scanlines.params import MAX_METRES, Param, Settings, auto_or, choice, number
from scanlines.steps.assemble import output_settings

__all__ = ["Surfaces"]


class Surfaces(PenalisedMethod):
    """The surfaces a scan sees as line segments, by one penalised-likelihood objective
    (module docstring)."""

    name = "surfaces"
    settings: ClassVar[Settings] = Settings(
        noise={
            "noise_sigma": Param(
                "auto",
                auto_or(number(low=0.0, low_open=True, high=MAX_METRES)),
                "range noise (m), or auto: the sensor profile's noise line, else the one learned",
            ),
        },
        segments={
            **OBJECTIVE,  # the penalised objective: partition's parameters, the same domains
            "footprint": Param(
                0.05,
                number(low=0.0, high=MAX_METRES),
                "wall length of one independent observation (m); 0: every return is one",
            ),
            "two_stage": Param(
                False,
                choice(True, False),
                "search the optimum in two stages (blocks first, then around their boundaries)",
            ),
        },
        output=output_settings(3),
    )
    presets: ClassVar[dict[str, dict[str, Any]]] = {}
    learns_noise = True

    @staticmethod
    def kernel(*arguments):
        return surfaces_stack(*arguments)
