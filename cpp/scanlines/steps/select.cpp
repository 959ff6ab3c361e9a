#include "scanlines/steps/select.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace scanlines {

namespace {
constexpr double INF = std::numeric_limits<double>::infinity();
}

Reals threshold_grid(double low, double high, double step, Index max_evaluations) {
    // Counted in double: a range of many steps must not overflow the integer.
    const double steps = std::floor((high - low) / step + 1e-9) + 1.0;
    Index count = max_evaluations;
    if (!(steps >= static_cast<double>(max_evaluations)))
        count = steps > 0.0 ? static_cast<Index>(steps) : 0;
    Reals out(static_cast<std::size_t>(std::max<Index>(count, 0)));
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = low + step * static_cast<double>(i);
    return out;
}

double criterion_value(Index criterion, double sse, Index segments, double log_n, double sigma,
                       double penalty) {
    if (sse != sse) sse = INF;
    if (criterion == SSE) return sse;
    return sse / (sigma * sigma) + penalty * log_n * static_cast<double>(segments);
}

Ints level_corners(const Ints& ranked, const Flags& accepted, Index level) {
    Ints out;
    for (Index j = 0; j < level; ++j)
        if (accepted[j]) out.push_back(ranked[j]);
    std::sort(out.begin(), out.end());
    return out;
}

std::pair<Index, Reals> best_level(Index criterion, const Reals& sse, const Ints& segments,
                                   const Ints& levels, Index n_points, double sigma,
                                   double penalty) {
    const std::size_t count = levels.size();
    Reals values(count);
    const double log_n = std::log(static_cast<double>(std::max<Index>(n_points, 2)));
    for (std::size_t t = 0; t < count; ++t) {
        Index level = levels[t];
        values[t] = criterion_value(criterion, sse[level], segments[level], log_n, sigma, penalty);
    }
    // np.argmin: the first smallest, or the first NaN.
    Index best = 0;
    for (std::size_t t = 0; t < count; ++t) {
        if (values[t] != values[t]) {
            best = static_cast<Index>(t);
            break;
        }
        if (values[t] < values[best]) best = static_cast<Index>(t);
    }
    return {best, values};
}

Ints rank_descending(const Reals& values) {
    // Largest first, NaN last, ties in index order.
    Ints order(values.size());
    std::iota(order.begin(), order.end(), Index{0});
    std::stable_sort(order.begin(), order.end(), [&](Index i, Index j) {
        double u = -values[i], v = -values[j];
        return u < v || (v != v && u == u);
    });
    return order;
}

Sweep start_sweep(const RunCost& cost, const Ints& start, const Ints& end, const Ints& candidates,
                  const Reals& scores, const Reals& grid, bool use_grid, Index max_evaluations) {
    const Index n = cost.moments.stride - 1;
    Reals magnitude(scores.size());
    for (std::size_t j = 0; j < scores.size(); ++j) magnitude[j] = std::fabs(scores[j]);
    Ints order = rank_descending(magnitude);
    const Index count = static_cast<Index>(order.size());
    Index useful = 0;
    if (!use_grid) {
        useful = std::min(count, max_evaluations);
    } else if (!grid.empty()) {
        double lowest = grid[0];  // np.min: NaN if any is NaN
        for (double t : grid) {
            if (t != t) {
                lowest = t;
                break;
            }
            lowest = std::min(lowest, t);
        }
        for (Index j = 0; j < count; ++j) useful += magnitude[order[j]] > lowest;
    }
    Sweep sweep;
    sweep.useful = useful;
    sweep.ranked.resize(useful);
    sweep.ranked_score.resize(useful);
    for (Index j = 0; j < useful; ++j) {
        sweep.ranked[j] = candidates[order[j]];
        sweep.ranked_score[j] = magnitude[order[j]];
    }
    sweep.run_end.assign(n, -1);
    sweep.cost_from.assign(n + 1, 0.0);
    double base = 0.0;
    for (std::size_t c = 0; c < start.size(); ++c) {
        sweep.run_end[start[c]] = end[c];
        sweep.cost_from[start[c]] = run_cost(cost, start[c], end[c]);
        base += sweep.cost_from[start[c]];
    }
    sweep.sse.assign(useful + 1, 0.0);
    sweep.segments.assign(useful + 1, 0);
    sweep.sse[0] = base;
    sweep.segments[0] = static_cast<Index>(start.size());
    sweep.accepted.assign(useful, false);
    sweep.parent_a.assign(useful, 0);
    sweep.parent_b.assign(useful, 0);
    return sweep;
}

Index extend_sweep(Sweep& sweep, const RunCost& cost, bool shared, Index done, Index upto) {
    Ints& run_end = sweep.run_end;
    Reals& cost_from = sweep.cost_from;
    for (Index j = done; j < upto; ++j) {
        Index c = sweep.ranked[j];
        Index a = c;
        while (run_end[a] < 0) --a;
        Index b = run_end[a];
        double gain = 0.0;
        if (!(c - a < (shared ? 2 : 1) || b - c < 2)) {
            sweep.accepted[j] = true;
            sweep.parent_a[j] = a;
            sweep.parent_b[j] = b;
            Index second = shared ? c : c + 1;
            run_end[a] = c;
            run_end[second] = b;
            double whole = cost_from[a];
            cost_from[a] = run_cost(cost, a, c);
            cost_from[second] = run_cost(cost, second, b);
            gain = cost_from[a] + cost_from[second] - whole;
        }
        sweep.sse[j + 1] = sweep.sse[j] + gain;
        sweep.segments[j + 1] = sweep.segments[j] + (sweep.accepted[j] ? 1 : 0);
    }
    return upto;
}

Levels sweep_levels(const RunCost& cost, const Ints& start, const Ints& end,
                    const Ints& candidates, const Reals& scores, const Reals& grid, bool use_grid,
                    Index max_evaluations, bool shared) {
    Sweep sweep =
        start_sweep(cost, start, end, candidates, scores, grid, use_grid, max_evaluations);
    extend_sweep(sweep, cost, shared, 0, sweep.useful);
    const Index useful = sweep.useful;
    Levels out;
    if (!use_grid) {
        Index count = std::min(useful, max_evaluations) + 1;
        out.levels.resize(count);
        out.thresholds.resize(count);
        for (Index t = 0; t < count; ++t) {
            out.levels[t] = t;
            out.thresholds[t] = t < useful ? sweep.ranked_score[t] : 0.0;
        }
    } else {
        out.thresholds = grid;
        // np.searchsorted(-ranked_score, -thresholds): the count of scores > t.
        Reals negated(sweep.ranked_score.size());
        for (std::size_t j = 0; j < negated.size(); ++j) negated[j] = -sweep.ranked_score[j];
        out.levels.resize(grid.size());
        for (std::size_t t = 0; t < grid.size(); ++t)
            out.levels[t] =
                std::lower_bound(negated.begin(), negated.end(), -grid[t]) - negated.begin();
    }
    out.ranked = std::move(sweep.ranked);
    out.accepted = std::move(sweep.accepted);
    out.sse = std::move(sweep.sse);
    out.segments = std::move(sweep.segments);
    return out;
}

}  // namespace scanlines
