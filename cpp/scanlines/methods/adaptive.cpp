#include "scanlines/methods/adaptive.hpp"

#include <algorithm>
#include <chrono>
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
Runs merge_by_criterion(const RunCost& cost, const Ints& a_in, const Ints& b_in,
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
Runs split_by_residual(const Reals& x, const Reals& y, Index fit, const Moments& moments,
                       const Ints& a, const Ints& b, const Ints& cluster, const Reals& tolerance,
                       Index min_points) {
    Runs out;
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

// The noise line the thresholds use: the noise_sigma override, else the sensor profile's
// noise or the scan's own (one constant, its value at the median range, with
// constant_noise).
NoiseLine scan_noise_model(const AdaptiveSettings::Noise& s, NoiseLine noise,
                           const Returns& returns, const Ints& gap) {
    if (!s.estimate_noise) return {s.noise_sigma, 0.0};
    noise = resolve_noise(noise, returns, gap);
    if (s.constant_noise) return {noise_at(noise, median(returns.r)), 0.0};
    return noise;
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
RunCost run_cost_of(const AdaptiveSettings::Segments& s, Moments moments, const Returns& returns,
                    const Reals& sigma) {
    if (s.criterion != BIC) return {s.fit, std::move(moments), {}, {}};
    Reals variances = variance_sums(sigma);
    return {s.fit, std::move(moments), inverse_square_sums(returns.r), std::move(variances)};
}

// Step 5's score at every position: the turn angle, or eq. 13.
Reals corner_scores(const Returns& returns, Index n_beams, double step, const Moments& moments,
                    const Ints& start, const Ints& end, Index window, Index kind) {
    if (kind == TURN) return turn_scores(returns.x, returns.y, moments, start, end, window);
    Ints gap = beam_gaps(returns.index, n_beams);
    return slope_scores(returns.r, gap, step, start, end, kind == DK_SIGNED);
}

struct Choice {
    Ints corners;
    double scale;
};

Index points_in(const Ints& start, const Ints& end) {
    Index n = 0;
    for (std::size_t c = 0; c < start.size(); ++c) n += end[c] - start[c] + 1;
    return n;
}

// The noise scale that the lines of a first choice of corners measure.
double measured_scale(const RunCost& cost, const Ints& start, const Ints& end,
                      const Ints& corners, bool shared) {
    Runs runs = cut_at(start, end, corners, shared);
    return std::max(residual_noise(cost, runs.a, runs.b, 1.0), 1e-3);
}

// choose_corners over every tried threshold (the "sse" criterion, or a fixed dkth_range).
Choice chosen_by_full_sweep(const RunCost& cost, const Ints& start, const Ints& end,
                            const Ints& candidates, const Reals& scores, bool rescale,
                            const AdaptiveSettings::Segments& s, const Reals& grid) {
    Levels swept = sweep_levels(cost, start, end, candidates, scores, grid, s.use_grid,
                                s.max_evaluations, s.shared_corner);
    const Index n_points = points_in(start, end);
    double scale = 1.0;
    Index best = best_level(s.criterion, swept.sse, swept.segments, swept.levels, n_points, scale,
                            s.penalty)
                     .first;
    Ints corners = level_corners(swept.ranked, swept.accepted, swept.levels[best]);
    if (rescale) {
        scale = measured_scale(cost, start, end, corners, s.shared_corner);
        best = best_level(s.criterion, swept.sse, swept.segments, swept.levels, n_points, scale,
                          s.penalty)
                   .first;
        corners = level_corners(swept.ranked, swept.accepted, swept.levels[best]);
    }
    return {corners, scale};
}

// Steps 5-7: corner candidates and the threshold sweep; the corners and the scale of the
// noise model (1, or with rescale the scale the lines of a first choice measure). Under
// "bic" the sweep stops where the choice is certain.
Choice choose_corners(const RunCost& cost, const Ints& start, const Ints& end,
                      const Reals& scores, bool rescale, const AdaptiveSettings::Segments& s,
                      const Reals& grid) {
    Ints candidates = peak_positions(scores, start, end);
    Reals candidate_scores(candidates.size());
    for (std::size_t j = 0; j < candidates.size(); ++j) candidate_scores[j] = scores[candidates[j]];
    if (s.criterion != BIC || s.use_grid)
        return chosen_by_full_sweep(cost, start, end, candidates, candidate_scores, rescale, s,
                                    grid);
    const Index n_points = points_in(start, end);
    Sweep sweep = start_sweep(cost, start, end, candidates, candidate_scores, grid, s.use_grid,
                              s.max_evaluations);
    auto [best, done] = sweep_decided(sweep, cost, s.shared_corner, 0, n_points, 1.0, s.penalty);
    Ints corners = level_corners(sweep.ranked, sweep.accepted, best);
    double scale = 1.0;
    if (rescale) {
        // Second choice with the noise scaled to the lines of the first.
        scale = measured_scale(cost, start, end, corners, s.shared_corner);
        best = sweep_decided(sweep, cost, s.shared_corner, done, n_points, scale, s.penalty).first;
        corners = level_corners(sweep.ranked, sweep.accepted, best);
    }
    return {corners, scale};
}

// Runs [a, b] (and the cluster of each) after cutting, refining, merging and bounding.
Runs segments(const Returns& returns, const RunCost& cost, const Ints& start, const Ints& end,
              const Ints& corners, double unit, const AdaptiveSettings& s, NoiseLine noise,
              const Reals& sigma) {
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    Runs runs = cut_at(start, end, corners, s.segments.shared_corner);
    if (!s.segments.shared_corner) std::tie(runs.a, runs.b) = refine_cuts(cost, runs.a, runs.b, runs.group);
    if (s.segments.merge) {
        double segment_cost =
            s.segments.penalty * std::log(static_cast<double>(std::max<Index>(returns.size(), 2))) * unit;
        runs = merge_by_criterion(cost, runs.a, runs.b, runs.group, segment_cost);
        if (s.segments.merge_chi2 > 0.0 && s.segments.fit != PAPER)
            runs = merge_by_chi_square(returns, cost.moments, runs.a, runs.b, runs.group, sigma,
                                       s.segments.merge_chi2, true);
    }
    if (s.segments.max_residual < INF) {
        Reals tolerance = residual_tolerances(returns.r, noise, s.segments.max_residual);
        runs = split_by_residual(x, y, s.segments.fit, cost.moments, runs.a, runs.b, runs.group, tolerance,
                                 s.output.min_points);
    }
    Runs out;
    for (std::size_t k = 0; k < runs.a.size(); ++k) {
        Index a = runs.a[k], b = runs.b[k];
        double dx = x[b] - x[a], dy = y[b] - y[a];
        double length = std::sqrt(dx * dx + dy * dy);
        if (b - a + 1 >= s.output.min_points && length >= s.output.min_length) {
            out.a.push_back(a);
            out.b.push_back(b);
            out.group.push_back(runs.group[k]);
        }
    }
    return out;
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

// The time since the last lap added to a stage's seconds (nothing without seconds).
class Laps {
public:
    explicit Laps(StageSeconds* seconds) : seconds_(seconds) {
        if (seconds_) last_ = Clock::now();
    }
    void end(AdaptiveStage stage) {
        if (!seconds_) return;
        Clock::time_point now = Clock::now();
        (*seconds_)[stage] += std::chrono::duration<double>(now - last_).count();
        last_ = now;
    }

private:
    using Clock = std::chrono::steady_clock;
    StageSeconds* seconds_;
    Clock::time_point last_;
};

}  // namespace

ScanResult adaptive_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                         const AdaptiveSettings& s, const Reals& grid, StageSeconds* seconds) {
    Laps laps(seconds);
    const Index n_beams = ranges.size;
    const double step = sensor.step;
    const bool full_circle = sensor.full_circle;
    double angle_min = sensor.angle_min;
    Returns returns = valid_returns(ranges, valid, sensor.cos, sensor.sin);
    if (returns.size() == 0) return empty_result({}, {});
    if (s.segments.fit == PAPER) {
        // y = kx + b depends on the frame: fit in the sensor frame, as the paper does.
        returns = turned(std::move(returns), angle_min);
        angle_min = 0.0;
    }
    Ints gap = beam_gaps(returns.index, n_beams);
    NoiseLine noise = scan_noise_model(s.noise, sensor.noise, returns, gap);
    const double typical = noise_at(noise, median(returns.r));
    BreakpointRule rule = breakpoint_rule(s.clustering, noise, step);
    const double margin = s.clustering.rule.noise_k * std::sqrt(2.0) * typical;
    laps.end(STAGE_NOISE);
    Denoised clean = denoise(std::move(returns), n_beams, step, full_circle, rule, s.clustering.denoise,
                             s.clustering.window, s.clustering.min_cluster_points, margin);
    laps.end(STAGE_DENOISE);
    if (clean.returns.size() == 0) return empty_result(clean.outliers, clean.outliers);
    Index window = s.segments.slope_window;
    if (s.segments.auto_slope_window)
        window = turn_window(clean.returns.x, clean.returns.y, clean.returns.index, typical);
    laps.end(STAGE_TURN_WINDOW);
    Clusters clusters = cluster_returns(std::move(clean.returns), n_beams, step, full_circle, rule,
                                        window, std::move(clean.breaks));
    laps.end(STAGE_CLUSTERS);
    const Returns& ret = clusters.returns;
    const Ints& start = clusters.start;
    const Ints& end = clusters.end;
    Reals sigma = return_sigmas(ret.r, noise);  // once: the criterion, merge, checks, covariances
    const RunCost cost = run_cost_of(s.segments, prefix_moments(ret.x, ret.y), ret, sigma);
    const Moments& moments = cost.moments;
    laps.end(STAGE_COSTS);
    Reals scores = corner_scores(ret, n_beams, step, moments, start, end, window, s.segments.corner_score);
    laps.end(STAGE_SCORES);
    const bool rescale = s.noise.estimate_noise && s.segments.criterion == BIC;
    Choice choice = choose_corners(cost, start, end, scores, rescale, s.segments, grid);
    laps.end(STAGE_CHOICE);
    const double unit =
        s.segments.criterion == BIC ? choice.scale * choice.scale : typical * typical;
    Runs runs = segments(ret, cost, start, end, choice.corners, unit, s, noise, sigma);
    laps.end(STAGE_SEGMENTS);
    const double check_sigma = s.events.corner_check ? choice.scale * typical : -1.0;
    Reals turn_sigmas;
    if (s.events.corner_check) turn_sigmas = direction_sigmas(ret, moments, runs.a, runs.b, sigma);
    auto [corner_beams, jumps] = junction_events(ret, s.segments.fit, moments, runs.a, runs.b, runs.group,
                                                 s.segments.shared_corner, clusters.ring, check_sigma,
                                                 turn_sigmas);
    Ints breakpoints = clusters.breakpoints;
    breakpoints.insert(breakpoints.end(), jumps.begin(), jumps.end());
    breakpoints = sorted_distinct(std::move(breakpoints));
    laps.end(STAGE_EVENTS);
    if (s.output.range_sigma == s.output.range_sigma)  // given: it replaces the noise line
        sigma.assign(ret.r.size(), s.output.range_sigma);
    ScanResult result =
        assemble(ret, s.segments.fit, moments, runs.a, runs.b, angle_min, sigma,
                 {std::move(breakpoints), std::move(corner_beams), std::move(clean.outliers)},
                 n_beams, full_circle);
    laps.end(STAGE_ASSEMBLY);
    return result;
}

Table adaptive_stack(const Stack& stack, const AdaptiveSettings& s, const Reals& grid,
                     StageSeconds* seconds) {
    Table table;
    for (Index row = 0; row < stack.rows; ++row)
        table.add(
            adaptive_scan(stack.row_ranges(row), stack.row_valid(row), stack, s, grid, seconds));
    return table;
}

}  // namespace scanlines
