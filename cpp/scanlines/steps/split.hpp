// Splitting runs of points into line segments (scanlines/steps/split.py).
#pragma once

#include <cmath>

#include "scanlines/core.hpp"
#include "scanlines/steps/fit.hpp"

namespace scanlines {

enum SplitReference : Index { CHORD = 0, LINE = 1 };

// Runs [a, b] and the group of each.
struct GroupedRuns {
    Ints a, b, group;
};

// Distance of point p to the chord from point a to point b (the segment between them).
double chord_distance(const Reals& x, const Reals& y, Index a, Index b, Index p);

// Orthogonal distance of point p to the line (rho, alpha).
inline double line_residual(const Reals& x, const Reals& y, Index p, double rho, double alpha) {
    return std::fabs(x[p] * std::cos(alpha) + y[p] * std::sin(alpha) - rho);
}

// Each run split recursively at its farthest point, depth first (iterative end-point fit).
GroupedRuns split_at_farthest(const Reals& x, const Reals& y, const Moments& moments,
                              const GroupedRuns& runs, double threshold, Index reference);

// Runs and their cluster number after cutting the clusters at corners.
GroupedRuns cut_at(const Ints& start, const Ints& end, const Ints& corners, bool shared);

}  // namespace scanlines
