// The adaptive-threshold line-segment extractor of the Electronics 2022 paper
// (scanlines/methods/adaptive.py has the method's description and its deviations).
#pragma once

#include <array>
#include <utility>

#include "scanlines/core.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/select.hpp"
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

// The settings resolved into the steps they select (adaptive_steps, once per stack): each
// stage of adaptive_scan is given its own group and reads no switch of another stage's.
struct AdaptiveSteps {
    bool sensor_frame;  // the paper's fit: y = kx + b depends on the frame, fit in the sensor's
    AdaptiveSettings::Noise noise;
    AdaptiveSettings::Clustering clustering;
    struct TurnWindow {
        Index fixed;
        bool measured;  // on the scan: auto
    } window;
    Index corner_score;
    struct Selection {
        Index fit;
        bool noise_units;  // bic: each run's error in noise variances; sse: in square metres
        bool decided;      // bic on the candidates' own scores: stop where the choice is certain
        bool rescale;      // choose again with the noise the first choice's lines measure
        Index criterion;
        double penalty;
        bool use_grid;
        Index max_evaluations;
        bool shared;
    } selection;
    struct Cutting {
        Index fit;
        bool shared, refine, merge;
        double penalty;
        double merge_chi2;    // 0: no chi-square merge (always so with the paper's fit)
        double max_residual;  // inf: no bound
        Index min_points;
        double min_length;
    } cutting;
    struct Junctions {
        Index fit;
        bool shared, corner_check;
    } junctions;
    struct Lines {
        Index fit;
        double range_sigma;  // NaN: each return's noise
    } lines;
};

// Every switch of the settings read once, into the steps it selects.
AdaptiveSteps adaptive_steps(const AdaptiveSettings& s);

// The adaptive method's own steps, bound for the tests (scanlines/methods/adaptive.py
// documents them; the rest of its own steps are adaptive.cpp's alone).

// ABD's lambda (radians) for beams step apart: abd_lambda="auto".
double auto_abd_lambda(double step);

// How far each return may lie from its segment's line: floor, or RESIDUAL_SIGMAS noise
// sigmas where that is more.
Reals residual_tolerances(const Reals& r, NoiseLine noise, double floor);

// Extend the sweep (from done inserted) until the "bic" choice with noise sigma is
// certain: (best level, inserted).
std::pair<Index, Index> sweep_decided(Sweep& sweep, const RunCost& cost, bool shared, Index done,
                                      Index n_points, double sigma, double penalty);

// The whole method on one scan; grid: the thresholds of a fixed dkth_range (else empty).
ScanResult adaptive_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                         const AdaptiveSteps& s, const Reals& grid);

Table adaptive_stack(const Stack& stack, const AdaptiveSettings& s, const Reals& grid);

#ifdef SCANLINES_STAGE_TIMES
// The stages of adaptive_scan, in order, for timing them (a build with
// -DSCANLINES_STAGE_TIMES=ON, for tools/benchmarks/stage_times.py).
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

// adaptive_stack with the time of each stage added to seconds.
Table adaptive_stack_timed(const Stack& stack, const AdaptiveSettings& s, const Reals& grid,
                           StageSeconds& seconds);
#endif

}  // namespace scanlines
