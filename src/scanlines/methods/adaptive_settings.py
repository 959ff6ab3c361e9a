"""The adaptive method's parameters, presets and the settings its kernel reads."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from scanlines.params import (
    MAX_COUNT,
    MAX_METRES,
    Param,
    auto_or,
    choice,
    float_pair,
    integer,
    number,
    optional,
    segment_params,
)
from scanlines.steps.breakpoints import BREAKPOINT_PARAMS, RULE_CODES
from scanlines.steps.corners import SCORE_CODES, SCORES
from scanlines.steps.denoise import DENOISE_CODES
from scanlines.steps.fit import FIT_CODES, FITS
from scanlines.steps.select import CRITERIA, CRITERION_CODES

PARAMETERS: dict[str, Param] = {
    **segment_params(3),
    **BREAKPOINT_PARAMS,
    "denoise": Param(
        "isolated", choice("isolated", "paper", "none"), "noise rule: isolated | paper | none"
    ),
    "window": Param(10, integer(1, 1000), "paper denoising: mean-filter window N (eq. 5)"),
    "corner_score": Param("turn", choice(*SCORES), "corner score: " + ", ".join(SCORES)),
    "slope_window": Param(
        "auto", auto_or(integer(2, 1000)), "turn score: points fitted on each side, or auto"
    ),
    "dkth_range": Param(
        "auto",
        auto_or(float_pair(high=MAX_METRES)),
        "threshold range (a, b), or auto: the candidates' scores",
    ),
    "dkth_step": Param(
        0.01, number(low=1e-9, high=MAX_METRES), "threshold step with a fixed range"
    ),
    "max_evaluations": Param(100, integer(1, 10_000), "most thresholds tried"),
    "criterion": Param("bic", choice(*CRITERIA), "selection: bic | sse (smallest SSE)"),
    "penalty": Param(4.0, number(low=0.0), "bic: cost of a segment, in ln(n) noise variances"),
    "noise_sigma": Param(
        "auto", auto_or(number(low=0.0, low_open=True)), "bic noise (m), or auto: estimated"
    ),
    "fit": Param("tls", choice(*FITS), "line fit: tls | paper (5-point OLS, eq. 15-17)"),
    "corner_split": Param(
        "refine", choice("refine", "shared"), "corner point: refine (best side) | shared"
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
    ),
    "min_cluster_points": Param(
        2, integer(1, MAX_COUNT), "isolated denoising: smaller clusters are dropped as noise"
    ),
    "noise_model": Param(
        "range",
        choice("range", "constant"),
        "noise: growing with range as measured (sensor profile or scan), or one constant",
    ),
}

PRESETS: dict[str, dict[str, Any]] = {
    "paper": {
        "breakpoints": "adaptive",
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


@dataclass(frozen=True)
class AdaptiveSettings:
    """The resolved parameters as the kernel reads them: codes for choices, radians.

    Where a parameter can be ``"auto"`` or ``None``, a flag says so (``auto_abd_lambda``,
    ``auto_slope_window``, ``estimate_noise``) and ``max_residual`` is ``inf`` for no
    bound; ``use_grid`` says whether a fixed ``dkth_range`` (the kernel's ``grid``)
    replaces the candidates' own scores.
    """

    breakpoints: int
    k: float
    noise_k: float
    line_k: float
    abd_lambda: float
    auto_abd_lambda: bool
    pdbs_c0: float
    jump_distance: float
    denoise: int
    window: int
    min_cluster_points: int
    corner_score: int
    slope_window: int
    auto_slope_window: bool
    use_grid: bool
    max_evaluations: int
    criterion: int
    penalty: float
    noise_sigma: float
    estimate_noise: bool
    constant_noise: bool
    fit: int
    shared_corner: bool
    merge: bool
    merge_chi2: float
    max_residual: float
    corner_check: bool
    min_points: int
    min_length: float
    range_sigma: float

    @classmethod
    def of(cls, params: Mapping[str, Any]) -> AdaptiveSettings:
        """The settings of resolved ``params``."""
        lam, window, sigma = params["abd_lambda"], params["slope_window"], params["noise_sigma"]
        return cls(
            breakpoints=RULE_CODES[params["breakpoints"]],
            k=params["k"],
            noise_k=params["noise_k"],
            line_k=params["line_k"],
            abd_lambda=math.nan if lam == "auto" else math.radians(lam),
            auto_abd_lambda=lam == "auto",
            pdbs_c0=params["pdbs_c0"],
            jump_distance=params["jump_distance"],
            denoise=DENOISE_CODES[params["denoise"]],
            window=params["window"],
            min_cluster_points=params["min_cluster_points"],
            corner_score=SCORE_CODES[params["corner_score"]],
            slope_window=0 if window == "auto" else window,
            auto_slope_window=window == "auto",
            use_grid=params["dkth_range"] != "auto",
            max_evaluations=params["max_evaluations"],
            criterion=CRITERION_CODES[params["criterion"]],
            penalty=params["penalty"],
            noise_sigma=math.nan if sigma == "auto" else sigma,
            estimate_noise=sigma == "auto",
            constant_noise=params["noise_model"] == "constant",
            fit=FIT_CODES[params["fit"]],
            shared_corner=params["corner_split"] == "shared",
            merge=params["merge"],
            merge_chi2=params["merge_chi2"],
            max_residual=math.inf if params["max_residual"] is None else params["max_residual"],
            corner_check=params["corner_check"],
            min_points=params["min_points"],
            min_length=params["min_length"],
            range_sigma=math.nan if params["range_sigma"] == "auto" else params["range_sigma"],
        )
