#include "scanlines/methods/adaptive.hpp"

#include <algorithm>
#ifdef SCANLINES_STAGE_TIMES
#include <chrono>
#endif
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/clusters.hpp"
#include "scanlines/steps/corners.hpp"
#include "scanlines/steps/denoise.hpp"
#include "scanlines/steps/events.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/merge.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"
#include "scanlines/steps/select.hpp"
#include "scanlines/steps/split.hpp"

namespace scanlines {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
constexpr double PI = 3.141592653589793;
const double DEGREE = PI / 180.0;  // math.radians(d) is d * (pi / 180)
const double ABD_LAMBDA_FLOOR = 10.0 * DEGREE;
const double MAX_BRIDGED_SHARE = std::sin(1.0 * DEGREE) / std::sin(14.0 * DEGREE);
// Candidates sweep_decided inserts between two checks of its bound.
constexpr Index SWEEP_CHUNK = 8;
// Fewest points of a run that residual_noise measures.
constexpr Index MIN_RUN_FOR_NOISE = 8;
// Noise sigmas a return may lie from its segment's line before the residual bound cuts.
constexpr double RESIDUAL_SIGMAS = 5.0;

}  // namespace

// The adaptive method's own steps, bound for the tests (adaptive.hpp).

double auto_abd_lambda(double step) {
    step = std::fabs(step);
    double bridged = std::asin(std::min(std::sin(step) / MAX_BRIDGED_SHARE, 1.0));
    return std::min(std::max(ABD_LAMBDA_FLOOR, step + bridged), 0.5 * PI);
}

Reals residual_tolerances(const Reals& r, NoiseLine noise, double floor) {
    Reals out(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) out[i] = std::max(floor, RESIDUAL_SIGMAS * noise_at(noise, r[i]));
    return out;
}

std::pair<Index, Index> sweep_decided(Sweep& sweep, const RunCost& cost, bool shared, Index done,
                                      Index n_points, double sigma, double penalty) {
    const double log_n = std::log(static_cast<double>(std::max<Index>(n_points, 2)));
    Index best = 0;
    double best_value = INF;
    Index scored = 0;
    while (true) {
        for (Index m = scored; m <= done; ++m) {
            double value =
                criterion_value(BIC, sweep.sse[m], sweep.segments[m], log_n, sigma, penalty);
            if (value < best_value) {
                best = m;
                best_value = value;
            }
        }
        scored = done + 1;
        if (done == sweep.useful ||
            !(penalty * log_n * static_cast<double>(sweep.segments[done]) < best_value))
            return {best, done};
        done = extend_sweep(sweep, cost, shared, done, std::min(done + SWEEP_CHUNK, sweep.useful));
    }
}

namespace {

// Running sums of 1 / r^2 (a micrometre floor keeps one absurd range harmless).
Reals inverse_square_sums(const Reals& r) {
    Reals out(r.size() + 1, 0.0);
    for (std::size_t i = 0; i < r.size(); ++i) {
        double ri = std::max(r[i], 1e-6);
        out[i + 1] = out[i] + 1.0 / (ri * ri);
    }
    return out;
}

// Running sums of sigma^2.
Reals variance_sums(const Reals& sigma) {
    Reals out(sigma.size() + 1, 0.0);
    for (std::size_t i = 0; i < sigma.size(); ++i) out[i + 1] = out[i] + sigma[i] * sigma[i];
    return out;
}

// Noise from the fits of the runs [a, b]: the median of sqrt(cost / (n - 2)) over runs of
// MIN_RUN_FOR_NOISE points or more; fallback without any such run.
double residual_noise(const RunCost& cost, const Ints& a, const Ints& b, double fallback) {
    Reals per_run;
    for (std::size_t k = 0; k < a.size(); ++k) {
        if (b[k] - a[k] + 1 >= MIN_RUN_FOR_NOISE) {
            double value = std::sqrt(run_cost(cost, a[k], b[k]) / static_cast<double>(b[k] - a[k] - 1));
            if (std::isfinite(value)) per_run.push_back(value);
        }
    }
    if (per_run.empty()) return fallback;
    return median(per_run);
}

// Each cut moved by one position where that fits better: (a, b).
std::pair<Ints, Ints> refine_cuts(const RunCost& cost, const Ints& a, const Ints& b,
                                  const Ints& owner) {
    const Index m = static_cast<Index>(a.size());
    Ints new_a = a, new_b = b;
    for (Index k = 0; k < m - 1; ++k) {
        if (owner[k] != owner[k + 1]) continue;
        double best_cost = INF;
        Index best_shift = 0;
        for (Index shift : {0, -1, 1}) {
            Index cut = b[k] + shift;
            if (cut - a[k] < 1 || b[k + 1] - cut - 1 < 1) continue;
            double total = run_cost(cost, a[k], cut) + run_cost(cost, cut + 1, b[k + 1]);
            if (total < best_cost - 1e-15) {  // NaN never wins
                best_cost = total;
                best_shift = shift;
            }
        }
        new_b[k] = b[k] + best_shift;
        new_a[k + 1] = new_b[k] + 1;
    }
    Flags too_short(m);
    for (Index k = 0; k < m; ++k) too_short[k] = new_b[k] - new_a[k] < 1;
    for (Index k = 0; k < m - 1; ++k)
        if (owner[k] == owner[k + 1] && (too_short[k] || too_short[k + 1])) {
            new_b[k] = b[k];
            new_a[k + 1] = a[k + 1];
        }
    return {new_a, new_b};
}

// Greedily merge the neighbour pair that lowers the criterion most, until none does.
GroupedRuns merge_by_criterion(const RunCost& cost, const Ints& a_in, const Ints& b_in,
                        const Ints& cluster_in, double segment_cost) {
    Ints a = a_in, b = b_in, cluster = cluster_in;
    Index m = static_cast<Index>(a.size());
    Reals part(m), joined(std::max<Index>(m - 1, 0), NAN);
    for (Index k = 0; k < m; ++k) part[k] = run_cost(cost, a[k], b[k]);
    for (Index k = 0; k < m - 1; ++k)
        if (cluster[k] == cluster[k + 1]) joined[k] = run_cost(cost, a[k], b[k + 1]);
    while (m >= 2) {
        Index best = -1;
        double best_change = INF;
        for (Index k = 0; k < m - 1; ++k) {
            double change = joined[k] - part[k] - part[k + 1] - segment_cost;
            if (change < best_change) {  // NaN (other cluster, no line) never wins
                best = k;
                best_change = change;
            }
        }
        if (best < 0 || !(best_change < 0.0)) break;
        b[best] = b[best + 1];
        part[best] = joined[best];
        for (Index k = best + 1; k < m - 1; ++k) {
            a[k] = a[k + 1];
            b[k] = b[k + 1];
            cluster[k] = cluster[k + 1];
            part[k] = part[k + 1];
        }
        for (Index k = best; k < m - 2; ++k) joined[k] = joined[k + 1];
        --m;
        for (Index k : {best - 1, best}) {
            if (0 <= k && k < m - 1) {
                bool same = cluster[k] == cluster[k + 1];
                double value = run_cost(cost, a[k], b[k + 1]);
                joined[k] = same ? value : NAN;
            }
        }
    }
    a.resize(m);
    b.resize(m);
    cluster.resize(m);
    return {a, b, cluster};
}

std::pair<double, Index> farthest_in_tolerances(const Reals& x, const Reals& y,
                                                const Reals& tolerance, Index lo, Index hi,
                                                double c, double s, double rho) {
    double worst = -1.0;
    Index worst_at = lo;
    for (Index p = lo; p <= hi; ++p) {
        double distance = std::fabs(x[p] * c + y[p] * s - rho) / tolerance[p];
        if (distance > worst) {
            worst = distance;
            worst_at = p;
        }
    }
    return {worst, worst_at};
}

std::pair<double, Index> farthest_from_chord_in_tolerances(const Reals& x, const Reals& y,
                                                           const Reals& tolerance, Index lo,
                                                           Index hi) {
    double dx = x[hi] - x[lo], dy = y[hi] - y[lo];
    double length = std::sqrt(dx * dx + dy * dy);
    if (length == 0.0) return {0.0, lo};
    double worst = -1.0;
    Index worst_at = lo;
    for (Index p = lo; p <= hi; ++p) {
        double distance = std::fabs((x[p] - x[lo]) * dy - (y[p] - y[lo]) * dx) / length / tolerance[p];
        if (distance > worst) {
            worst = distance;
            worst_at = p;
        }
    }
    return {worst, worst_at};
}

// Cut runs at their worst point until every point is within its tolerance.
GroupedRuns split_by_residual(const Reals& x, const Reals& y, Index fit, const Moments& moments,
                       const Ints& a, const Ints& b, const Ints& cluster, const Reals& tolerance,
                       Index min_points) {
    GroupedRuns out;
    const Index shortest = std::max<Index>(min_points, 1);
    std::vector<std::pair<Index, Index>> stack;
    for (std::size_t k = 0; k < a.size(); ++k) {
        stack.assign(1, {a[k], b[k]});
        while (!stack.empty()) {
            auto [lo, hi] = stack.back();
            stack.pop_back();
            if (hi - lo + 1 < shortest) continue;
            Line line = fit_run(fit, moments, lo, hi);
            auto [worst, worst_at] = farthest_in_tolerances(
                x, y, tolerance, lo, hi, std::cos(line.alpha), std::sin(line.alpha), line.rho);
            if (worst <= 1.0) {
                out.a.push_back(lo);
                out.b.push_back(hi);
                out.group.push_back(cluster[k]);
                continue;
            }
            if (worst_at - lo < shortest || hi - worst_at < shortest) {
                auto [bend, bend_at] = farthest_from_chord_in_tolerances(x, y, tolerance, lo, hi);
                if (bend > 1.0 && bend_at - lo >= shortest && hi - bend_at >= shortest) {
                    stack.push_back({bend_at + 1, hi});
                    stack.push_back({lo, bend_at});
                    continue;
                }
            }
            stack.push_back({worst_at + 1, hi});  // right part after the left
            stack.push_back({lo, worst_at - 1});
        }
    }
    return out;
}

// The noise line the thresholds use and its value at the median range.
struct ScanNoise {
    NoiseLine line;
    double typical;
};

// The noise_sigma override, else the sensor profile's noise or the scan's own (one
// constant, its value at the median range, with constant_noise).
ScanNoise scan_noise(const AdaptiveSettings::Noise& s, NoiseLine noise, const Returns& returns,
                     Index n_beams) {
    if (!s.estimate_noise) {
        noise = {s.noise_sigma, 0.0};
    } else {
        noise = resolve_noise(noise, returns, beam_gaps(returns.index, n_beams));
        if (s.constant_noise) noise = {noise_at(noise, median(returns.r)), 0.0};
    }
    return {noise, noise_at(noise, median(returns.r))};
}

// The clustering rule of the settings with the range noise.
BreakpointRule breakpoint_rule(const AdaptiveSettings::Clustering& s, NoiseLine noise,
                               double step) {
    const RuleSpec& rule = s.rule;
    double lambda = s.auto_abd_lambda ? auto_abd_lambda(step) : rule.abd_lambda;
    return make_rule(rule.breakpoints, rule.k, rule.noise_k, rule.line_k, lambda, rule.pdbs_c0,
                     rule.jump_distance, noise);
}

// The run cost of the criterion: in noise units for BIC (each run's error over its
// returns' mean noise variance, sigma per return, and incidence), square metres for SSE.
RunCost run_cost_of(const AdaptiveSteps::Selection& s, const Returns& returns,
                    const Reals& sigma) {
    Moments moments = prefix_moments(returns.x, returns.y);
    if (!s.noise_units) return {s.fit, std::move(moments), {}, {}};
    Reals variances = variance_sums(sigma);
    return {s.fit, std::move(moments), inverse_square_sums(returns.r), std::move(variances)};
}

// The corner score at every position: the turn angle, or the paper's eq. 13.
Reals corner_scores(const Clusters& clusters, Index n_beams, double step, const Moments& moments,
                    Index window, Index kind) {
    const Returns& ret = clusters.returns;
    if (kind == TURN) return turn_scores(ret.x, ret.y, moments, clusters.start, clusters.end, window);
    Ints gap = beam_gaps(ret.index, n_beams);
    return slope_scores(ret.r, gap, step, clusters.start, clusters.end, kind == DK_SIGNED);
}

// The corner candidates: the peaks of the scores, and their scores.
struct Candidates {
    Ints positions;
    Reals scores;
};

Candidates corner_candidates(const Reals& scores, const Clusters& clusters) {
    Candidates out{peak_positions(scores, clusters.start, clusters.end), {}};
    out.scores.resize(out.positions.size());
    for (std::size_t j = 0; j < out.positions.size(); ++j) out.scores[j] = scores[out.positions[j]];
    return out;
}

// The chosen corners, the scale of the noise model (1, or with rescale the scale the lines
// of a first choice measure) and the variance unit of a segment's cost (the scaled noise's
// in noise units, the typical noise's in square metres).
struct Choice {
    Ints corners;
    double scale, unit;
};

Index points_in(const Ints& start, const Ints& end) {
    Index n = 0;
    for (std::size_t c = 0; c < start.size(); ++c) n += end[c] - start[c] + 1;
    return n;
}

// The noise scale that the lines of a first choice of corners measure.
double measured_scale(const RunCost& cost, const Ints& start, const Ints& end,
                      const Ints& corners, bool shared) {
    GroupedRuns runs = cut_at(start, end, corners, shared);
    return std::max(residual_noise(cost, runs.a, runs.b, 1.0), 1e-3);
}

// The threshold sweep's choice over every tried threshold (the "sse" criterion, or a fixed
// dkth_range).
Choice chosen_by_full_sweep(const RunCost& cost, const Clusters& clusters,
                            const Candidates& candidates, double typical,
                            const AdaptiveSteps::Selection& s, const Reals& grid) {
    const Ints& start = clusters.start;
    const Ints& end = clusters.end;
    Levels swept = sweep_levels(cost, start, end, candidates.positions, candidates.scores, grid,
                                s.use_grid, s.max_evaluations, s.shared);
    const Index n_points = points_in(start, end);
    double scale = 1.0;
    Index best = best_level(s.criterion, swept.sse, swept.segments, swept.levels, n_points, scale,
                            s.penalty)
                     .first;
    Ints corners = level_corners(swept.ranked, swept.accepted, swept.levels[best]);
    if (s.rescale) {
        scale = measured_scale(cost, start, end, corners, s.shared);
        best = best_level(s.criterion, swept.sse, swept.segments, swept.levels, n_points, scale,
                          s.penalty)
                   .first;
        corners = level_corners(swept.ranked, swept.accepted, swept.levels[best]);
    }
    return {corners, scale, s.noise_units ? scale * scale : typical * typical};
}

// The threshold sweep's choice by the "bic" criterion on the candidates' own scores: the
// sweep stops where the choice is certain.
Choice chosen_by_decided_sweep(const RunCost& cost, const Clusters& clusters,
                               const Candidates& candidates, const AdaptiveSteps::Selection& s,
                               const Reals& grid) {
    const Ints& start = clusters.start;
    const Ints& end = clusters.end;
    const Index n_points = points_in(start, end);
    Sweep sweep = start_sweep(cost, start, end, candidates.positions, candidates.scores, grid,
                              false, s.max_evaluations);
    auto [best, done] = sweep_decided(sweep, cost, s.shared, 0, n_points, 1.0, s.penalty);
    Ints corners = level_corners(sweep.ranked, sweep.accepted, best);
    double scale = 1.0;
    if (s.rescale) {
        // Second choice with the noise scaled to the lines of the first.
        scale = measured_scale(cost, start, end, corners, s.shared);
        best = sweep_decided(sweep, cost, s.shared, done, n_points, scale, s.penalty).first;
        corners = level_corners(sweep.ranked, sweep.accepted, best);
    }
    return {corners, scale, scale * scale};
}

// The segments: runs [a, b] (and the cluster of each) after cutting at the corners,
// refining, merging and bounding the residuals, small ones dropped.
GroupedRuns segments(const Clusters& clusters, const RunCost& cost, const Choice& choice,
                     const AdaptiveSteps::Cutting& s, NoiseLine noise, const Reals& sigma) {
    const Returns& ret = clusters.returns;
    GroupedRuns runs = cut_at(clusters.start, clusters.end, choice.corners, s.shared);
    if (s.refine) std::tie(runs.a, runs.b) = refine_cuts(cost, runs.a, runs.b, runs.group);
    if (s.merge) {
        double segment_cost =
            s.penalty * std::log(static_cast<double>(std::max<Index>(ret.size(), 2))) * choice.unit;
        runs = merge_by_criterion(cost, runs.a, runs.b, runs.group, segment_cost);
        if (s.merge_chi2 > 0.0)
            runs = merge_by_chi_square(ret, cost.moments, runs.a, runs.b, runs.group, sigma,
                                       s.merge_chi2, true);
    }
    if (s.max_residual < INF) {
        Reals tolerance = residual_tolerances(ret.r, noise, s.max_residual);
        runs = split_by_residual(ret.x, ret.y, s.fit, cost.moments, runs.a, runs.b, runs.group,
                                 tolerance, s.min_points);
    }
    GroupedRuns kept;  // those of min_points returns and min_length
    for (std::size_t k = 0; k < runs.a.size(); ++k) {
        Index a = runs.a[k], b = runs.b[k];
        double dx = ret.x[b] - ret.x[a], dy = ret.y[b] - ret.y[a];
        double length = std::sqrt(dx * dx + dy * dy);
        if (b - a + 1 >= s.min_points && length >= s.min_length) {
            kept.a.push_back(a);
            kept.b.push_back(b);
            kept.group.push_back(runs.group[k]);
        }
    }
    return kept;
}

// Standard deviation of each segment's direction, from the noise (sigma per return) and
// its residuals.
Reals direction_sigmas(const Returns& returns, const Moments& moments, const Ints& a,
                       const Ints& b, const Reals& sigma) {
    Lines lines = fit_many(TLS, moments, a, b);
    Reals covariance = run_covariances(returns.r, returns.x, returns.y, lines.rho, lines.alpha, a, b, sigma, true);
    Reals out(a.size());
    for (std::size_t k = 0; k < a.size(); ++k) out[k] = std::sqrt(covariance[4 * k + 3]);
    return out;
}

// The clustering's breakpoints with the corners and jumps between the kept segments; with the corner check, two lines whose turn is within noise (sigma of the scaled
// noise model at the typical range) of their directions meet at no corner.
Events junctions(const Clusters& clusters, const Moments& moments, const GroupedRuns& runs,
                 const Reals& sigma, double noise, const AdaptiveSteps::Junctions& s) {
    const Returns& ret = clusters.returns;
    Reals turn_sigmas;
    if (s.corner_check) turn_sigmas = direction_sigmas(ret, moments, runs.a, runs.b, sigma);
    auto [corners, jumps] =
        junction_events(ret, s.fit, moments, runs.a, runs.b, runs.group, s.shared, clusters.ring,
                        s.corner_check ? noise : -1.0, turn_sigmas);
    Ints breakpoints = clusters.breakpoints;
    breakpoints.insert(breakpoints.end(), jumps.begin(), jumps.end());
    return {sorted_distinct(std::move(breakpoints)), std::move(corners), {}};
}

}  // namespace

AdaptiveSteps adaptive_steps(const AdaptiveSettings& s) {
    const AdaptiveSettings::Segments& g = s.segments;
    const bool paper_fit = g.fit == PAPER;
    const bool bic = g.criterion == BIC;
    AdaptiveSteps out;
    out.sensor_frame = paper_fit;
    out.noise = s.noise;
    out.clustering = s.clustering;
    out.window = {g.slope_window, g.auto_slope_window};
    out.corner_score = g.corner_score;
    out.selection = {g.fit,          bic,          bic && !g.use_grid,
                     bic && s.noise.estimate_noise, g.criterion, g.penalty,
                     g.use_grid,     g.max_evaluations, g.shared_corner};
    out.cutting = {g.fit,          g.shared_corner, !g.shared_corner,
                   g.merge,        g.penalty,       paper_fit ? 0.0 : g.merge_chi2,
                   g.max_residual, s.output.min_points, s.output.min_length};
    out.junctions = {g.fit, g.shared_corner, s.events.corner_check};
    out.lines = {g.fit, s.output.range_sigma};
    return out;
}

ScanResult adaptive_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                         const AdaptiveSteps& s, const Reals& grid) {
    const Index n_beams = ranges.size;
    const double step = sensor.step;
    const bool full_circle = sensor.full_circle;

    // The points, the first beam along x; turned into the sensor frame for the paper's fit
    // (y = kx + b depends on the frame).
    Returns returns = valid_returns(ranges, valid, sensor.cos, sensor.sin);
    if (returns.size() == 0) return empty_result({}, {});
    if (s.sensor_frame) returns = turned(std::move(returns), sensor.angle_min);
    const double angle_min = s.sensor_frame ? 0.0 : sensor.angle_min;

    // Step 1: the noise line every threshold uses, and the clustering rule with it.
    const ScanNoise noise = scan_noise(s.noise, sensor.noise, returns, n_beams);
    const BreakpointRule rule = breakpoint_rule(s.clustering, noise.line, step);

    // Step 2: noise points dropped (reported as outliers) or moved; the rule's margin is the
    // noise of a range difference.
    const double margin = s.clustering.rule.noise_k * std::sqrt(2.0) * noise.typical;
    Denoised clean = denoise(std::move(returns), n_beams, step, full_circle, rule,
                             s.clustering.denoise, s.clustering.window,
                             s.clustering.min_cluster_points, margin);
    if (clean.returns.size() == 0) return empty_result(clean.outliers, clean.outliers);

    // Step 3: the clusters; a closed ring is anchored with the turn score's window (points
    // fitted on each side: fixed, or measured on the scan).
    const Index window = s.window.measured ? turn_window(clean.returns.x, clean.returns.y,
                                                         clean.returns.index, noise.typical)
                                           : s.window.fixed;
    Clusters clusters = cluster_returns(std::move(clean.returns), n_beams, step, full_circle,
                                        rule, window, std::move(clean.breaks));

    // Each return's noise (criterion, merge, corner check, covariances); a run's cost.
    Reals sigma = return_sigmas(clusters.returns.r, noise.line);
    const RunCost cost = run_cost_of(s.selection, clusters.returns, sigma);

    // Step 4: the corner score at every position, its peaks the candidates.
    Reals scores = corner_scores(clusters, n_beams, step, cost.moments, window, s.corner_score);
    Candidates candidates = corner_candidates(scores, clusters);

    // Step 5: the threshold sweep's choice of corners.
    Choice choice = s.selection.decided
                        ? chosen_by_decided_sweep(cost, clusters, candidates, s.selection, grid)
                        : chosen_by_full_sweep(cost, clusters, candidates, noise.typical,
                                               s.selection, grid);

    // Step 6: the segments, cut at the corners, refined, merged, bounded; small ones dropped.
    GroupedRuns runs = segments(clusters, cost, choice, s.cutting, noise.line, sigma);

    // Step 7: breakpoints, and the corners and jumps between the segments.
    Events events = junctions(clusters, cost.moments, runs, sigma, choice.scale * noise.typical,
                              s.junctions);
    events.outliers = std::move(clean.outliers);

    // Step 8: the lines and their covariances, from the noise line or range_sigma.
    if (s.lines.range_sigma == s.lines.range_sigma) sigma.assign(sigma.size(), s.lines.range_sigma);
    return assemble(clusters.returns, s.lines.fit, cost.moments, runs.a, runs.b, angle_min, sigma,
                    std::move(events), n_beams, full_circle);
}

Table adaptive_stack(const Stack& stack, const AdaptiveSettings& s, const Reals& grid) {
    return each_row(stack, adaptive_scan, adaptive_steps(s), grid);
}

#ifdef SCANLINES_STAGE_TIMES
// Stage timing, for tools/benchmarks/stage_times.py only: a build with
// -DSCANLINES_STAGE_TIMES=ON. adaptive_scan's calls in its order, a lap after each stage;
// the tool checks that the table is adaptive_stack's.

const std::array<const char*, N_ADAPTIVE_STAGES> ADAPTIVE_STAGE_NAMES = {
    "returns, noise, rule",
    "denoise",
    "turn window",
    "clustering",
    "sigmas, running sums, costs",
    "corner scores",
    "candidates + sweep + choice",
    "cut, refine, merge, split",
    "corner beams",
    "assembly (fits, covariances)",
};

namespace {

// The time since the last lap added to a stage's seconds.
class Laps {
public:
    explicit Laps(StageSeconds& seconds) : seconds_(seconds), last_(Clock::now()) {}
    void end(AdaptiveStage stage) {
        Clock::time_point now = Clock::now();
        seconds_[stage] += std::chrono::duration<double>(now - last_).count();
        last_ = now;
    }

private:
    using Clock = std::chrono::steady_clock;
    StageSeconds& seconds_;
    Clock::time_point last_;
};

ScanResult adaptive_scan_timed(View<double> ranges, View<bool> valid, const Stack& sensor,
                               const AdaptiveSteps& s, const Reals& grid, Laps& laps) {
    const Index n_beams = ranges.size;
    const double step = sensor.step;
    const bool full_circle = sensor.full_circle;
    Returns returns = valid_returns(ranges, valid, sensor.cos, sensor.sin);
    if (returns.size() == 0) return empty_result({}, {});
    if (s.sensor_frame) returns = turned(std::move(returns), sensor.angle_min);
    const double angle_min = s.sensor_frame ? 0.0 : sensor.angle_min;
    const ScanNoise noise = scan_noise(s.noise, sensor.noise, returns, n_beams);
    const BreakpointRule rule = breakpoint_rule(s.clustering, noise.line, step);
    laps.end(STAGE_NOISE);
    const double margin = s.clustering.rule.noise_k * std::sqrt(2.0) * noise.typical;
    Denoised clean = denoise(std::move(returns), n_beams, step, full_circle, rule,
                             s.clustering.denoise, s.clustering.window,
                             s.clustering.min_cluster_points, margin);
    laps.end(STAGE_DENOISE);
    if (clean.returns.size() == 0) return empty_result(clean.outliers, clean.outliers);
    const Index window = s.window.measured ? turn_window(clean.returns.x, clean.returns.y,
                                                         clean.returns.index, noise.typical)
                                           : s.window.fixed;
    laps.end(STAGE_TURN_WINDOW);
    Clusters clusters = cluster_returns(std::move(clean.returns), n_beams, step, full_circle,
                                        rule, window, std::move(clean.breaks));
    laps.end(STAGE_CLUSTERS);
    Reals sigma = return_sigmas(clusters.returns.r, noise.line);
    const RunCost cost = run_cost_of(s.selection, clusters.returns, sigma);
    laps.end(STAGE_COSTS);
    Reals scores = corner_scores(clusters, n_beams, step, cost.moments, window, s.corner_score);
    laps.end(STAGE_SCORES);
    Candidates candidates = corner_candidates(scores, clusters);
    Choice choice = s.selection.decided
                        ? chosen_by_decided_sweep(cost, clusters, candidates, s.selection, grid)
                        : chosen_by_full_sweep(cost, clusters, candidates, noise.typical,
                                               s.selection, grid);
    laps.end(STAGE_CHOICE);
    GroupedRuns runs = segments(clusters, cost, choice, s.cutting, noise.line, sigma);
    laps.end(STAGE_SEGMENTS);
    Events events = junctions(clusters, cost.moments, runs, sigma, choice.scale * noise.typical,
                              s.junctions);
    events.outliers = std::move(clean.outliers);
    laps.end(STAGE_EVENTS);
    if (s.lines.range_sigma == s.lines.range_sigma) sigma.assign(sigma.size(), s.lines.range_sigma);
    ScanResult result = assemble(clusters.returns, s.lines.fit, cost.moments, runs.a, runs.b,
                                 angle_min, sigma, std::move(events), n_beams, full_circle);
    laps.end(STAGE_ASSEMBLY);
    return result;
}

}  // namespace

Table adaptive_stack_timed(const Stack& stack, const AdaptiveSettings& s, const Reals& grid,
                           StageSeconds& seconds) {
    const AdaptiveSteps steps = adaptive_steps(s);
    Table table;
    for (Index row = 0; row < stack.rows; ++row) {
        Laps laps(seconds);
        table.add(adaptive_scan_timed(stack.row_ranges(row), stack.row_valid(row), stack, steps,
                                      grid, laps));
    }
    return table;
}
#endif

}  // namespace scanlines
