#include "scanlines/steps/split.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace scanlines {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

// Largest distance of an interior point of run [a, b] from its chord, and that point.
std::pair<double, Index> farthest_from_chord(const Reals& x, const Reals& y, Index a, Index b) {
    double worst = -INF;
    Index at = a;
    for (Index p = a + 1; p < b; ++p) {
        double distance = chord_distance(x, y, a, b, p);
        if (distance > worst) {  // NaN never wins
            worst = distance;
            at = p;
        }
    }
    return {worst, at};
}

double farthest_from_line(const Reals& x, const Reals& y, const Moments& moments, Index a, Index b) {
    Line line = tls_run(moments, a, b);
    double c = std::cos(line.alpha), s = std::sin(line.alpha);
    double worst = -INF;
    for (Index p = a + 1; p < b; ++p) {
        double distance = std::fabs(x[p] * c + y[p] * s - line.rho);
        if (distance > worst) worst = distance;
    }
    return worst;
}

// Last position of the first part when run [a, b] is split at at: at or at - 1.
Index split_side(const Reals& x, const Reals& y, const Moments& moments, Index a, Index b, Index at) {
    if (at - a < 2) return at;
    if (b - at < 2) return at - 1;
    Line left = tls_run(moments, a, at - 1);
    double to_left = line_residual(x, y, at, left.rho, left.alpha);
    Line right = tls_run(moments, at + 1, b);
    double to_right = line_residual(x, y, at, right.rho, right.alpha);
    return to_left > to_right ? at - 1 : at;
}

}  // namespace

double chord_distance(const Reals& x, const Reals& y, Index a, Index b, Index p) {
    double dx = x[b] - x[a], dy = y[b] - y[a];
    double px = x[p] - x[a], py = y[p] - y[a];
    double length2 = dx * dx + dy * dy;
    double t = 0.0;
    if (length2 > 0.0) {
        t = (px * dx + py * dy) / length2;
        if (t < 0.0)
            t = 0.0;
        else if (t > 1.0)
            t = 1.0;
    }
    return std::hypot(px - t * dx, py - t * dy);
}

GroupedRuns split_at_farthest(const Reals& x, const Reals& y, const Moments& moments,
                              const GroupedRuns& runs, double threshold, Index reference) {
    GroupedRuns out;
    struct Pending {
        Index lo, hi, group;
    };
    std::vector<Pending> stack;
    for (Index k = static_cast<Index>(runs.a.size()) - 1; k >= 0; --k)
        stack.push_back({runs.a[k], runs.b[k], runs.group[k]});
    while (!stack.empty()) {
        Pending run = stack.back();
        stack.pop_back();
        if (run.hi - run.lo >= 2) {
            auto [worst, at] = farthest_from_chord(x, y, run.lo, run.hi);
            if (reference == LINE) worst = farthest_from_line(x, y, moments, run.lo, run.hi);
            if (worst > threshold) {
                Index cut = split_side(x, y, moments, run.lo, run.hi, at);
                stack.push_back({cut + 1, run.hi, run.group});
                stack.push_back({run.lo, cut, run.group});
                continue;
            }
        }
        out.a.push_back(run.lo);
        out.b.push_back(run.hi);
        out.group.push_back(run.group);
    }
    return out;
}

GroupedRuns cut_at(const Ints& start, const Ints& end, const Ints& corners, bool shared) {
    GroupedRuns out;
    out.a = start;
    for (Index c : corners) out.a.push_back(c + (shared ? 0 : 1));
    out.b = corners;
    out.b.insert(out.b.end(), end.begin(), end.end());
    std::sort(out.a.begin(), out.a.end());
    std::sort(out.b.begin(), out.b.end());
    for (Index value : out.a)
        out.group.push_back(
            static_cast<Index>(std::upper_bound(start.begin(), start.end(), value) - start.begin()) - 1);
    return out;
}

}  // namespace scanlines
