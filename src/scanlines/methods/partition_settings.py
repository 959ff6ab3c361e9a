"""The partition method's fixed bounds, parameters, presets and the settings its kernel reads."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from scanlines.params import MAX_METRES, Param, auto_or, number, optional, segment_params

EVENT_SIGMAS = 3.0
"""Standard deviations by which a turn must be resolved and within which lines meet."""

CUT_SIGMAS = 5.0
"""Standard deviations of a range difference beyond the surface bound at which two
neighbouring returns cannot share a segment (Gaussian noise crosses it once in about 1.7
million pairs, so noise alone never cuts a wall)."""

GRAZING_ANGLE = math.radians(10.0)
"""Smallest angle between a beam and a surface at which neighbouring returns still lie on
one surface (80 deg of incidence: the breakpoint bound of Borges and Aldon)."""

PARAMETERS: dict[str, Param] = {
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
    **segment_params(4),
    "max_rho_sigma": Param(
        None,
        optional(number(low=0.0, low_open=True, high=MAX_METRES)),
        "keep only segments whose rho standard deviation is at most this (m), or None: all",
    ),
    "noise_sigma": Param(
        "auto",
        auto_or(number(low=0.0, low_open=True, high=MAX_METRES)),
        "range noise (m), or auto: the sensor profile's noise line, else the scan's own",
    ),
}

PRESETS: dict[str, dict[str, Any]] = {
    "repeatable": {"max_rho_sigma": 0.02},
}


@dataclass(frozen=True)
class PartitionSettings:
    """The resolved parameters as the kernel reads them (NaN: not given, inf: no bound)."""

    penalty: float
    clutter_cost: float
    model_error: float
    min_points: int
    min_length: float
    range_sigma: float
    max_rho_sigma: float
    noise_sigma: float

    @classmethod
    def of(cls, params: Mapping[str, Any]) -> PartitionSettings:
        """The settings of resolved ``params``."""
        bound, sigma, covariance = (
            params["max_rho_sigma"],
            params["noise_sigma"],
            params["range_sigma"],
        )
        return cls(
            penalty=params["penalty"],
            clutter_cost=params["clutter_cost"],
            model_error=params["model_error"],
            min_points=params["min_points"],
            min_length=params["min_length"],
            range_sigma=math.nan if covariance == "auto" else covariance,
            max_rho_sigma=math.inf if bound is None else bound,
            noise_sigma=math.nan if sigma == "auto" else sigma,
        )
