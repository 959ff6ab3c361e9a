"""The adaptive method's parameters (with the fields its kernel reads) and presets."""

from __future__ import annotations

from typing import Any

import numpy as np

from scanlines.params import (
    MAX_COUNT,
    MAX_METRES,
    KernelField,
    Param,
    as_float,
    auto_or,
    choice,
    coded,
    flag,
    float_pair,
    integer,
    number,
    optional,
    radians,
    segment_params,
)
from scanlines.steps.breakpoints import BREAKPOINT_PARAMS
from scanlines.steps.corners import SCORE_CODES, SCORES
from scanlines.steps.denoise import DENOISE_CODES
from scanlines.steps.fit import FIT_CODES, FITS
from scanlines.steps.select import CRITERIA, CRITERION_CODES


def _count_or_zero(value: Any) -> np.int64:
    """An integer, ``"auto"`` as 0 (its flag says so)."""
    return np.int64(0 if value == "auto" else value)


def _fixed_range(value: Any) -> np.bool_:
    """Whether a fixed threshold range (the kernel's ``grid``) replaces the candidates'
    own scores."""
    return np.bool_(value != "auto")


PARAMETERS: dict[str, Param] = {
    **segment_params(3),
    **BREAKPOINT_PARAMS,
    "denoise": Param(
        "isolated",
        choice("isolated", "paper", "none"),
        "noise rule: isolated | paper | none",
        (coded(DENOISE_CODES),),
    ),
    "window": Param(10, integer(1, 1000), "paper denoising: mean-filter window N (eq. 5)"),
    "corner_score": Param(
        "turn", choice(*SCORES), "corner score: " + ", ".join(SCORES), (coded(SCORE_CODES),)
    ),
    "slope_window": Param(
        "auto",
        auto_or(integer(2, 1000)),
        "turn score: points fitted on each side, or auto",
        (KernelField("", _count_or_zero), flag("auto_slope_window", "auto")),
    ),
    "dkth_range": Param(
        "auto",
        auto_or(float_pair(high=MAX_METRES)),
        "threshold range (a, b), or auto: the candidates' scores",
        (KernelField("use_grid", _fixed_range),),  # the thresholds: the kernel's grid
    ),
    "dkth_step": Param(
        0.01, number(low=1e-9, high=MAX_METRES), "threshold step with a fixed range", ()
    ),
    "max_evaluations": Param(100, integer(1, 10_000), "most thresholds tried"),
    "criterion": Param(
        "bic",
        choice(*CRITERIA),
        "selection: bic | sse (smallest SSE)",
        (coded(CRITERION_CODES),),
    ),
    "penalty": Param(4.0, number(low=0.0), "bic: cost of a segment, in ln(n) noise variances"),
    "noise_sigma": Param(
        "auto",
        auto_or(number(low=0.0, low_open=True)),
        "bic noise (m), or auto: estimated",
        (as_float(), flag("estimate_noise", "auto")),
    ),
    "fit": Param(
        "tls",
        choice(*FITS),
        "line fit: tls | paper (5-point OLS, eq. 15-17)",
        (coded(FIT_CODES),),
    ),
    "corner_split": Param(
        "refine",
        choice("refine", "shared"),
        "corner point: refine (best side) | shared",
        (flag("shared_corner", "shared"),),
    ),
    "merge": Param(True, choice(True, False), "merge collinear neighbours"),
    "merge_chi2": Param(
        9.21,
        number(low=0.0),
        "merge neighbours whose (rho, alpha) agree within this chi-square (2 dof; covariances "
        "from the noise model and the residuals; 0: off)",
    ),
    "max_residual": Param(
        0.1,
        optional(number(low=0.0, low_open=True)),
        "largest point-to-line distance (m), or 5 noise sigmas at the point's range where "
        "that is more",
    ),
    "corner_check": Param(
        True, choice(True, False), "lines that do not meet near their ends are a jump, not a corner"
    ),
    "abd_lambda": Param(
        "auto",
        auto_or(BREAKPOINT_PARAMS["abd_lambda"].check),
        "ABD: worst incidence angle, degrees, or auto: 10, more on scans coarser than 0.67 deg",
        (radians(), flag("auto_abd_lambda", "auto")),
    ),
    "min_cluster_points": Param(
        2, integer(1, MAX_COUNT), "isolated denoising: smaller clusters are dropped as noise"
    ),
    "noise_model": Param(
        "range",
        choice("range", "constant"),
        "noise: growing with range as measured (sensor profile or scan), or one constant",
        (flag("constant_noise", "constant"),),
    ),
}

PRESETS: dict[str, dict[str, Any]] = {
    "paper": {
        "breakpoints": "paper",
        "k": 3.0,
        "noise_k": 0.0,
        "line_k": 0.0,
        "denoise": "paper",
        "window": 10,
        "corner_score": "dk",
        "dkth_range": (0.0, 0.052),
        "dkth_step": 0.01,
        "max_evaluations": 100,
        "criterion": "sse",
        "fit": "paper",
        "corner_split": "shared",
        "merge": False,
        "corner_check": False,
        "max_residual": None,
        "min_points": 2,
        "min_cluster_points": 1,
        "min_length": 0.0,
    },
}
