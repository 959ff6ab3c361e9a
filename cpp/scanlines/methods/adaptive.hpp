// The adaptive-threshold line-segment extractor of the Electronics 2022 paper
// (scanlines/methods/adaptive.py has the method's description and its deviations).
#pragma once

#include <array>

#include "scanlines/core.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

// The kernel's settings, grouped as scanlines/methods/adaptive.py declares them.
struct AdaptiveSettings {
    struct Noise {
        double noise_sigma;  // used unless estimate_noise
        bool estimate_noise;
        bool constant_noise;
    } noise;
    struct Clustering {
        RuleSpec rule;         // abd_lambda in radians, unless auto_abd_lambda
        bool auto_abd_lambda;
        Index denoise, window, min_cluster_points;
    } clustering;
    struct Segments {
        Index corner_score, slope_window;
        bool auto_slope_window;
        bool use_grid;  // the thresholds of a fixed dkth_range, else the candidates' scores
        Index max_evaluations;
        Index criterion;
        double penalty;
        Index fit;
        bool shared_corner, merge;
        double merge_chi2;
        double max_residual;  // inf: no bound
    } segments;
    struct Events {
        bool corner_check;
    } events;
    OutputBounds output;
};

// The stages of adaptive_scan, in order, for timing them (tools/benchmarks/stage_times.py).
enum AdaptiveStage : int {
    STAGE_NOISE,
    STAGE_DENOISE,
    STAGE_TURN_WINDOW,
    STAGE_CLUSTERS,
    STAGE_COSTS,
    STAGE_SCORES,
    STAGE_CHOICE,
    STAGE_SEGMENTS,
    STAGE_EVENTS,
    STAGE_ASSEMBLY,
    N_ADAPTIVE_STAGES
};
extern const std::array<const char*, N_ADAPTIVE_STAGES> ADAPTIVE_STAGE_NAMES;
using StageSeconds = std::array<double, N_ADAPTIVE_STAGES>;

// The whole method on one scan; grid: the thresholds of a fixed dkth_range (else empty).
// With seconds, the time of each stage is added to it.
ScanResult adaptive_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                         const AdaptiveSettings& s, const Reals& grid,
                         StageSeconds* seconds = nullptr);

Table adaptive_stack(const Stack& stack, const AdaptiveSettings& s, const Reals& grid,
                     StageSeconds* seconds = nullptr);

}  // namespace scanlines
