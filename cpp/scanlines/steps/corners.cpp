#include "scanlines/steps/corners.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/noise.hpp"

namespace scanlines {

namespace {

// Mask of positions with a neighbour on both sides inside their cluster.
Flags interior_mask(const Ints& start, const Ints& end, Index n) {
    Flags inside(n, true);
    for (Index s : start) inside[s] = false;
    for (Index e : end) inside[e] = false;
    return inside;
}

// Unit direction of the fitted line of run [a, b], oriented from a towards b.
std::pair<double, double> heading(const Reals& x, const Reals& y, const Moments& moments, Index a,
                                  Index b) {
    Axis axis = tls_axis(moments, a, b);
    if (-axis.ny * (x[b] - x[a]) + axis.nx * (y[b] - y[a]) >= 0.0) return {-axis.ny, axis.nx};
    return {axis.ny, -axis.nx};
}

}  // namespace

Reals slope_scores(const Reals& r, const Ints& gap, double step, const Ints& start,
                   const Ints& end, bool is_signed) {
    const Index n = static_cast<Index>(r.size());
    Reals score(n, 0.0);
    if (n < 3) return score;
    Reals slope(n - 1);
    for (Index i = 0; i < n - 1; ++i) {
        double denominator = r[i] * step * static_cast<double>(gap[i]);
        slope[i] = denominator != 0.0 ? (r[i + 1] - r[i]) / denominator : NAN;
        if (!is_signed) slope[i] = std::fabs(slope[i]);
    }
    Flags inside = interior_mask(start, end, n);
    for (Index i = 1; i < n - 1; ++i) {
        double value = slope[i - 1] - slope[i];
        if (inside[i] && std::isfinite(value)) score[i] = value;
    }
    return score;
}

Reals turn_scores(const Reals& x, const Reals& y, const Moments& moments, const Ints& start,
                  const Ints& end, Index window) {
    const Index n = static_cast<Index>(x.size());
    Reals score(n, 0.0), after_x(n), after_y(n);
    for (std::size_t c = 0; c < start.size(); ++c) {
        for (Index p = start[c]; p <= end[c]; ++p)
            std::tie(after_x[p], after_y[p]) = heading(x, y, moments, p, std::min(p + window, end[c]));
        for (Index p = start[c] + 1; p < end[c]; ++p) {
            double bx, by;
            if (p - window >= start[c]) {
                bx = after_x[p - window];
                by = after_y[p - window];
            } else {
                std::tie(bx, by) = heading(x, y, moments, start[c], p);
            }
            double ux = after_x[p], uy = after_y[p];
            score[p] = std::fabs(std::atan2(bx * uy - by * ux, bx * ux + by * uy));
        }
    }
    return score;
}

Index turn_window(const Reals& x, const Reals& y, const Ints& index, double sigma) {
    Reals steps = neighbour_steps(x, y);
    Reals adjacent;
    for (std::size_t p = 0; p < steps.size(); ++p)
        if (index[p + 1] - index[p] == 1) adjacent.push_back(steps[p]);
    if (adjacent.empty()) return 3;
    double spacing = median(adjacent);
    double wanted = spacing > 0.0 ? 3 + 6 * sigma / spacing : std::numeric_limits<double>::infinity();
    double bounded = std::min(std::max(wanted, 3.0), static_cast<double>(MAX_TURN_WINDOW));
    return static_cast<Index>(std::nearbyint(bounded));  // Python's round: half to even
}

Ints peak_positions(const Reals& score, const Ints& start, const Ints& end) {
    const Index n = static_cast<Index>(score.size());
    Ints out;
    if (n < 3) return out;
    Flags inside = interior_mask(start, end, n);
    for (Index i = 1; i < n - 1; ++i) {
        double here = std::fabs(score[i]);
        if (inside[i] && here > std::fabs(score[i - 1]) && here > std::fabs(score[i + 1]))
            out.push_back(i);
    }
    return out;
}

Index ring_anchor(const Reals& x, const Reals& y, Index window) {
    const Index n = static_cast<Index>(x.size());
    const Index half = n / 2;
    const Ints start{0}, end{n - 1};
    Reals direct = turn_scores(x, y, prefix_moments(x, y), start, end, window);
    Reals turned_x, turned_y;
    for (Index k = 0; k < n; ++k) {
        Index p = (half + k) % n;
        turned_x.push_back(x[p]);
        turned_y.push_back(y[p]);
    }
    Reals turned = turn_scores(turned_x, turned_y, prefix_moments(turned_x, turned_y), start, end,
                               window);
    Index best = 0;
    double best_score = -std::numeric_limits<double>::infinity();
    for (Index p = 0; p < n; ++p) {
        Index shifted = py_mod(p - half, n);
        double value = direct[p];
        if (std::min(p, n - 1 - p) < std::min(shifted, n - 1 - shifted)) value = turned[shifted];
        if (value > best_score) {
            best = p;
            best_score = value;
        }
    }
    return best;
}

}  // namespace scanlines
