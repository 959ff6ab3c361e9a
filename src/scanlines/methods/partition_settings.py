"""The partition method's parameters (the fields its kernel reads) and presets."""

from __future__ import annotations

from typing import Any

from scanlines.params import MAX_METRES, Param, auto_or, number, optional, segment_params

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
