// The adaptive-threshold line-segment extractor of the Electronics 2022 paper
// (scanlines/methods/adaptive.py has the method's description and its deviations).
#pragma once

#include <array>

#include "scanlines/core.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

// The kernel's settings (the fields scanlines/methods/adaptive_settings.py declares).
struct AdaptiveSettings {
    Index min_points;
    double min_length;
    double range_sigma;  // NaN: the noise line
    Index breakpoints;
    double k, noise_k, line_k;
    double abd_lambda;  // radians, unless auto_abd_lambda
    bool auto_abd_lambda;
    double pdbs_c0, jump_distance;
    Index denoise, window;
    Index corner_score, slope_window;
    bool auto_slope_window;
    bool use_grid;  // the thresholds of a fixed dkth_range, else the candidates' scores
    Index max_evaluations;
    Index criterion;
    double penalty;
    double noise_sigma;  // used unless estimate_noise
    bool estimate_noise;
    Index fit;
    bool shared_corner, merge;
    double merge_chi2;
    double max_residual;  // inf: no bound
    bool corner_check;
    Index min_cluster_points;
    bool constant_noise;
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
