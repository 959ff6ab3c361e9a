#include "scanlines/steps/split.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

Runs split_at_farthest(const Reals& x, const Reals& y, const Moments& moments, const Runs& runs,
                       double threshold, Index reference) {
    Runs out;
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

Runs cut_at(const Ints& start, const Ints& end, const Ints& corners, bool shared) {
    Runs out;
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

}  // namespace scanlines
