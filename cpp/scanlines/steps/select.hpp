// The threshold sweep over dkth and its selection criterion (scanlines/steps/select.py
// documents the sweep and the criteria).
#pragma once

#include <utility>

#include "scanlines/core.hpp"
#include "scanlines/steps/fit.hpp"

namespace scanlines {

enum Criterion : Index { BIC = 0, SSE = 1 };

// low, low + step, ... up to high, at most max_evaluations values.
Reals threshold_grid(double low, double high, double step, Index max_evaluations);

// The criterion of one segmentation (smaller is better); NaN SSE counts as inf. log_n is
// ln(max(n_points, 2)).
double criterion_value(Index criterion, double sse, Index segments, double log_n, double sigma,
                       double penalty);

// Sorted positions of the accepted candidates among the level best.
Ints level_corners(const Ints& ranked, const Flags& accepted, Index level);

// Index of the best tried threshold (the first on a tie) and every criterion value.
std::pair<Index, Reals> best_level(Index criterion, const Reals& sse, const Ints& segments,
                                   const Ints& levels, Index n_points, double sigma,
                                   double penalty);

// Order of values from largest to smallest, equal values in index order.
Ints rank_descending(const Reals& values);

// A threshold sweep in progress: ranked candidates best first (ranked_score their
// |score|), of which the first useful can change a cut; sse[m] and segments[m] describe
// the cut with the m best (filled up to the candidates inserted so far); accepted[j]:
// candidate j cuts, parent_a/b[j] the run it cut; run_end[a] the end of the current run
// starting at a (-1 inside a run), cost_from[a] its cost.
struct Sweep {
    Ints ranked;
    Reals ranked_score;
    Index useful = 0;
    Flags accepted;
    Ints parent_a, parent_b;
    Reals sse;
    Ints segments;
    Ints run_end;
    Reals cost_from;
};

// A sweep of the clusters [start, end] with no candidate inserted yet: the thresholds
// grid with use_grid, else the candidates' own scores (at most max_evaluations).
Sweep start_sweep(const RunCost& cost, const Ints& start, const Ints& end, const Ints& candidates,
                  const Reals& scores, const Reals& grid, bool use_grid, Index max_evaluations);

// Insert candidates done .. upto - 1 and score each cut; returns upto.
Index extend_sweep(Sweep& sweep, const RunCost& cost, bool shared, Index done, Index upto);

// Every cut of the clusters that a threshold makes, scored: sse[m] and segments[m] of the
// cut with the m best ranked candidates; levels[t] the cut of each tried threshold.
struct Levels {
    Ints ranked;
    Flags accepted;
    Reals sse;
    Ints segments;
    Reals thresholds;
    Ints levels;
};
Levels sweep_levels(const RunCost& cost, const Ints& start, const Ints& end,
                    const Ints& candidates, const Reals& scores, const Reals& grid, bool use_grid,
                    Index max_evaluations, bool shared);

}  // namespace scanlines
