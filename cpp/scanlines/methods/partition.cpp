#include "scanlines/methods/partition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

namespace {

constexpr double PI = 3.141592653589793;
constexpr double INF = std::numeric_limits<double>::infinity();
constexpr double EVENT_SIGMAS = 3.0;
constexpr double CUT_SIGMAS = 5.0;
const double GRAZING_ANGLE = 10.0 * (PI / 180.0);  // as math.radians(10.0) rounds
constexpr Index LOOK_BACK = 256;
constexpr int ROUNDS = 3;

// Prefix sums (rows 0..n) of w, wx, wy, wxx, wxy, wyy and the held count; row-major x 7.
struct Sums {
    Reals v;
    double at(Index row, int column) const { return v[7 * row + column]; }
};

struct Runs {
    Ints a, b;
};

Sums weighted_sums(const Reals& x, const Reals& y, const Reals& sigma, double model_error,
                   const Flags& held) {
    const Index n = static_cast<Index>(x.size());
    Sums out{Reals(static_cast<std::size_t>(7 * (n + 1)), 0.0)};
    const double floor = model_error * model_error;
    double* o = out.v.data();
    for (Index p = 0; p < n; ++p) {
        double w = held[p] ? 1.0 / (sigma[p] * sigma[p] + floor) : 0.0;
        double u = x[p] - x[0], v = y[p] - y[0];
        const double* prev = o + 7 * p;
        double* next = o + 7 * (p + 1);
        next[0] = prev[0] + w;
        next[1] = prev[1] + w * u;
        next[2] = prev[2] + w * v;
        next[3] = prev[3] + w * u * u;
        next[4] = prev[4] + w * u * v;
        next[5] = prev[5] + w * v * v;
        next[6] = prev[6] + (held[p] ? 1.0 : 0.0);
    }
    return out;
}

struct Scatter {
    double w, mx, my, sxx, sxy, syy;
};

Scatter scatter(const Sums& sums, Index a, Index b) {
    double w = sums.at(b + 1, 0) - sums.at(a, 0);
    double mx = (sums.at(b + 1, 1) - sums.at(a, 1)) / w;
    double my = (sums.at(b + 1, 2) - sums.at(a, 2)) / w;
    double sxx = sums.at(b + 1, 3) - sums.at(a, 3) - w * mx * mx;
    double sxy = sums.at(b + 1, 4) - sums.at(a, 4) - w * mx * my;
    double syy = sums.at(b + 1, 5) - sums.at(a, 5) - w * my * my;
    return {w, mx, my, sxx, sxy, syy};
}

// The smaller and larger eigenvalue of the scatter [[sxx, sxy], [sxy, syy]].
std::pair<double, double> eigenvalues(double sxx, double sxy, double syy) {
    double half = 0.5 * (sxx + syy);
    double spread = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
    return {std::max(half - spread, 0.0), half + spread};
}

struct FittedLine {
    double rho, alpha, direction_variance, w;
};

FittedLine line_of(const Sums& sums, Index a, Index b, double x0, double y0) {
    Scatter s = scatter(sums, a, b);
    double alpha = 0.5 * std::atan2(-2.0 * s.sxy, s.syy - s.sxx);
    double rho = (s.mx + x0) * std::cos(alpha) + (s.my + y0) * std::sin(alpha);
    if (rho < 0.0) {
        rho = -rho;
        alpha = alpha + PI;
    }
    double large = eigenvalues(s.sxx, s.sxy, s.syy).second;
    return {rho, alpha, large > 0.0 ? 1.0 / large : INF, s.w};
}

// Whether returns p and q (beams apart) may lie on one surface.
bool continuous(const Returns& ret, Index p, Index q, Index beams, double step,
                const Reals& sigma, double sigmas) {
    double turn = static_cast<double>(beams) * step;
    if (turn >= GRAZING_ANGLE) return false;
    double reach = std::min(ret.r[p], ret.r[q]) * std::sin(turn) / std::sin(GRAZING_ANGLE - turn);
    double apart = std::hypot(ret.x[q] - ret.x[p], ret.y[q] - ret.y[p]);
    double spread = sigmas * std::sqrt(sigma[p] * sigma[p] + sigma[q] * sigma[q]);
    return apart <= reach + spread;
}

Runs optimal_runs(const Sums& sums, const Flags& opens, double penalty, double clutter_cost,
                  Index min_points) {
    const Index n = static_cast<Index>(sums.v.size() / 7) - 1;
    Reals best(n + 1), cost(n + 1);
    Ints start(n + 1), candidates(n + 1), expires(n + 1, n + 1);
    best[0] = 0.0;
    Index count = 0;
    const double* prefix = sums.v.data();
    for (Index t = 1; t <= n; ++t) {
        if (opens[t - 1]) count = 0;
        candidates[count++] = t - 1;
        // The prefix sums up to t, read once (the same arithmetic as scatter(sums, s, t - 1)).
        double end[7];
        std::copy(prefix + 7 * t, prefix + 7 * t + 7, end);
        double best_t = best[t - 1] + clutter_cost;
        Index start_t = -1;
        Index kept = 0;
        for (Index c = 0; c < count; ++c) {
            const Index s = candidates[c];
            if (expires[s] <= t || t - s > LOOK_BACK) continue;
            candidates[kept] = s;
            double value = INF;
            const double* from = prefix + 7 * s;
            const double held = end[6] - from[6];
            if (held >= static_cast<double>(min_points)) {
                const double w = end[0] - from[0];
                const double mx = (end[1] - from[1]) / w;
                const double my = (end[2] - from[2]) / w;
                const double sxx = end[3] - from[3] - w * mx * mx;
                const double sxy = end[4] - from[4] - w * mx * my;
                const double syy = end[5] - from[5] - w * my * my;
                value = best[s] + 0.5 * eigenvalues(sxx, sxy, syy).first;
                value += clutter_cost * (static_cast<double>(t - s) - held);
                if (value + penalty < best_t) {
                    best_t = value + penalty;
                    start_t = s;
                }
            }
            cost[kept] = value;
            ++kept;
        }
        best[t] = best_t;
        start[t] = start_t;
        count = kept;
        for (Index c = 0; c < count; ++c)  // prune the starts that t dominates (PELT)
            if (cost[c] >= best_t && cost[c] < INF && expires[candidates[c]] > n)
                expires[candidates[c]] = t + min_points;
    }
    Runs out;
    Index t = n;
    while (t > 0) {
        if (start[t] < 0) {
            --t;
            continue;
        }
        out.a.push_back(start[t]);
        out.b.push_back(t - 1);
        t = start[t];
    }
    std::reverse(out.a.begin(), out.a.end());
    std::reverse(out.b.begin(), out.b.end());
    return out;
}

double run_cost(const Sums& sums, Index a, Index b, double penalty, double clutter_cost) {
    double held = sums.at(b + 1, 6) - sums.at(a, 6);
    Scatter s = scatter(sums, a, b);
    return 0.5 * eigenvalues(s.sxx, s.sxy, s.syy).first +
           clutter_cost * (static_cast<double>(b - a + 1) - held) + penalty;
}

Runs joined_runs(const Sums& sums, const Flags& opens, const Runs& runs, double penalty,
                 double clutter_cost) {
    const std::size_t count = runs.a.size();
    if (count < 2) return runs;
    Runs out = runs;
    std::size_t m = 0;
    for (std::size_t k = 1; k < count; ++k) {
        bool touching = out.b[m] + 1 == runs.a[k] && !opens[runs.a[k]];
        if (touching && run_cost(sums, out.a[m], runs.b[k], penalty, clutter_cost) <=
                            run_cost(sums, out.a[m], out.b[m], penalty, clutter_cost) +
                                run_cost(sums, runs.a[k], runs.b[k], penalty, clutter_cost)) {
            out.b[m] = runs.b[k];
        } else {
            ++m;
            out.a[m] = runs.a[k];
            out.b[m] = runs.b[k];
        }
    }
    out.a.resize(m + 1);
    out.b.resize(m + 1);
    return out;
}

// Whether each return lies in its run's fit (returns outside the runs: true).
Flags inside_fit(const Reals& x, const Reals& y, const Sums& sums, const Reals& sigma,
                 double model_error, const Runs& runs, double clutter_cost) {
    Flags out(x.size(), true);
    const double floor = model_error * model_error;
    for (std::size_t k = 0; k < runs.a.size(); ++k) {
        FittedLine line = line_of(sums, runs.a[k], runs.b[k], x[0], y[0]);
        double c = std::cos(line.alpha), si = std::sin(line.alpha);
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) {
            double off = x[p] * c + y[p] * si - line.rho;
            out[p] = 0.5 * off * off / (sigma[p] * sigma[p] + floor) <= clutter_cost;
        }
    }
    return out;
}

Runs trimmed_runs(const Flags& held, Runs runs) {
    for (std::size_t k = 0; k < runs.a.size(); ++k) {
        while (runs.a[k] < runs.b[k] && !held[runs.a[k]]) ++runs.a[k];
        while (runs.b[k] > runs.a[k] && !held[runs.b[k]]) --runs.b[k];
    }
    return runs;
}

struct Partition {
    Runs runs;
    Flags held;
    Sums sums;
    Ints gap;
};

Partition best_partition(const Returns& ret, const Reals& sigma, Index n_beams, double step,
                         const PartitionSettings& s) {
    const Index n = ret.size();
    const Reals& x = ret.x;
    const Reals& y = ret.y;
    Ints gap = beam_gaps(ret.index, n_beams);
    Flags opens(n);
    opens[0] = true;
    for (Index p = 1; p < n; ++p) {
        bool bridged = gap[p - 1] <= MAX_BRIDGED_GAP;
        bool step_ok = continuous(ret, p - 1, p, gap[p - 1], step, sigma, CUT_SIGMAS);
        opens[p] = !(bridged && step_ok);
    }
    Flags held(n, true);
    Runs runs;
    for (int round = 0; round < ROUNDS; ++round) {
        Sums sums = weighted_sums(x, y, sigma, s.model_error, held);
        runs = optimal_runs(sums, opens, s.penalty, s.clutter_cost, s.min_points);
        runs = joined_runs(sums, opens, runs, s.penalty, s.clutter_cost);
        Flags fits = inside_fit(x, y, sums, sigma, s.model_error, runs, s.clutter_cost);
        bool changed = fits != held;
        held = fits;
        if (!changed) break;
    }
    Sums sums = weighted_sums(x, y, sigma, s.model_error, held);
    runs = trimmed_runs(held, runs);
    std::fill(held.begin(), held.end(), false);  // returns outside the runs are outliers too
    for (std::size_t k = 0; k < runs.a.size(); ++k)
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) held[p] = true;
    Flags fits = inside_fit(x, y, sums, sigma, s.model_error, runs, s.clutter_cost);
    for (Index p = 0; p < n; ++p) held[p] = held[p] && fits[p];
    runs = trimmed_runs(held, runs);  // a run's end may have left its fit
    return {runs, held, sums, gap};
}

// The position of the corner where neighbouring segments i and j meet, or -1.
Index corner_between(const Returns& ret, const Sums& sums, const Reals& sigma, const Runs& runs,
                     Index i, Index j) {
    const Reals& x = ret.x;
    const Reals& y = ret.y;
    FittedLine li = line_of(sums, runs.a[i], runs.b[i], x[0], y[0]);
    FittedLine lj = line_of(sums, runs.a[j], runs.b[j], x[0], y[0]);
    double turn = lj.alpha - li.alpha;
    turn -= PI * std::floor(turn / PI + 0.5);  // undirected: in [-pi/2, pi/2)
    if (std::fabs(turn) <= EVENT_SIGMAS * std::sqrt(li.direction_variance + lj.direction_variance))
        return -1;
    double det = std::sin(lj.alpha - li.alpha);
    double cx = (li.rho * std::sin(lj.alpha) - lj.rho * std::sin(li.alpha)) / det;
    double cy = (lj.rho * std::cos(li.alpha) - li.rho * std::cos(lj.alpha)) / det;
    Index end = runs.b[i], begin = runs.a[j];
    double spacing = std::hypot(x[begin] - x[end], y[begin] - y[end]);
    double reach = spacing + EVENT_SIGMAS * std::max(sigma[end], sigma[begin]);
    double to_end = std::hypot(cx - x[end], cy - y[end]);
    double to_begin = std::hypot(cx - x[begin], cy - y[begin]);
    if (to_end > reach || to_begin > reach) return -1;
    return to_end <= to_begin ? end : begin;
}

struct ScanShape {
    bool full_circle, ring;
    Index n_beams;
};

std::pair<Ints, Ints> partition_events(const Returns& ret, const Sums& sums, const Reals& sigma,
                                       const Runs& runs, const Ints& gap, double step,
                                       ScanShape shape) {
    const Index n = ret.size();
    Ints breakpoints, corners;
    Ints owner(n, -1);
    for (std::size_t k = 0; k < runs.a.size(); ++k)
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) owner[p] = static_cast<Index>(k);
    const Index last = shape.ring ? n : n - 1;
    for (Index p = 0; p < last; ++p) {
        Index q = (p + 1) % n;
        if (owner[p] >= 0 && owner[p] == owner[q]) continue;
        Index beams = p < n - 1 ? gap[p] : py_mod(ret.index[0] - ret.index[n - 1], shape.n_beams);
        bool across_gap = p < n - 1 && gap[p] > MAX_BRIDGED_GAP;
        if (across_gap || !continuous(ret, p, q, beams, step, sigma, EVENT_SIGMAS)) {
            breakpoints.push_back(ret.index[p]);
        } else if (owner[p] >= 0 && owner[q] >= 0) {
            Index at = corner_between(ret, sums, sigma, runs, owner[p], owner[q]);
            if (at >= 0) corners.push_back(ret.index[at]);
        }
    }
    if (shape.full_circle && !shape.ring) breakpoints.push_back(ret.index[n - 1]);
    std::sort(breakpoints.begin(), breakpoints.end());
    return {breakpoints, corners};
}

// A full circle's returns rotated to start after their widest gap, and whether they close
// into a ring.
std::pair<Returns, bool> seam_at_widest_gap(Returns ret, const Ints& gap, Index n_beams) {
    const Index n = ret.size();
    if (n < 2) return {ret, false};
    Index widest = 0;
    for (std::size_t p = 0; p < gap.size(); ++p)
        if (gap[p] > gap[widest]) widest = static_cast<Index>(p);
    Index closing = py_mod(ret.index[0] - ret.index[n - 1], n_beams);
    if (closing >= gap[widest]) return {ret, closing <= MAX_BRIDGED_GAP};
    return {rotated(ret, widest + 1), gap[widest] <= MAX_BRIDGED_GAP};
}

// Which runs hold at least min_points returns in their fit and are at least min_length long.
Flags kept_runs(const Returns& ret, const Flags& held, const Runs& runs, Index min_points,
                double min_length) {
    Flags keep(runs.a.size());
    for (std::size_t k = 0; k < runs.a.size(); ++k) {
        Index count = 0;
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) count += held[p];
        double length = std::hypot(ret.x[runs.b[k]] - ret.x[runs.a[k]],
                                   ret.y[runs.b[k]] - ret.y[runs.a[k]]);
        keep[k] = count >= min_points && length >= min_length;
    }
    return keep;
}

// The result without the segments whose rho standard deviation exceeds max_rho_sigma.
ScanResult well_determined(const ScanResult& result, double max_rho_sigma) {
    ScanResult out;
    out.breakpoints = result.breakpoints;
    out.corners = result.corners;
    out.outliers = result.outliers;
    for (Index k = 0; k < result.segments(); ++k) {
        if (!(result.covariances[4 * k] <= max_rho_sigma * max_rho_sigma)) continue;
        out.first.push_back(result.first[k]);
        out.last.push_back(result.last[k]);
        out.n_points.push_back(result.n_points[k]);
        auto line = result.lines.begin() + LINE_COLUMNS * k;
        out.lines.insert(out.lines.end(), line, line + LINE_COLUMNS);
        auto cov = result.covariances.begin() + 4 * k;
        out.covariances.insert(out.covariances.end(), cov, cov + 4);
        out.end_kinds.push_back(result.end_kinds[2 * k]);
        out.end_kinds.push_back(result.end_kinds[2 * k + 1]);
    }
    return out;
}

}  // namespace

ScanResult partition_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                          const PartitionSettings& s) {
    const Index n_beams = ranges.size;
    Returns ret = valid_returns(ranges, valid, sensor.cos, sensor.sin);
    if (ret.size() == 0) return empty_result({}, {});
    Ints gap = beam_gaps(ret.index, n_beams);
    NoiseLine noise = sensor.noise;
    if (s.noise_sigma == s.noise_sigma) noise = {s.noise_sigma, 0.0};
    noise = resolve_noise(noise, ret, gap);
    bool ring = false;
    if (sensor.full_circle) std::tie(ret, ring) = seam_at_widest_gap(ret, gap, n_beams);
    Reals sigma(ret.r.size());
    for (std::size_t p = 0; p < sigma.size(); ++p) sigma[p] = noise_at(noise, ret.r[p]);
    Partition part = best_partition(ret, sigma, n_beams, sensor.step, s);
    if (ring && part.runs.a.size() > 1) {
        // A closed ring: cut it where the first optimum had a boundary, and solve again.
        Index shift = part.runs.b[0] + 1;
        ret = rotated(ret, shift);
        std::rotate(sigma.begin(), sigma.begin() + shift, sigma.end());
        part = best_partition(ret, sigma, n_beams, sensor.step, s);
    }
    auto [breakpoints, corners] = partition_events(
        ret, part.sums, sigma, part.runs, part.gap, sensor.step, {sensor.full_circle, ring, n_beams});
    Ints outliers;
    for (Index p = 0; p < ret.size(); ++p)
        if (!part.held[p]) outliers.push_back(ret.index[p]);
    Flags keep = kept_runs(ret, part.held, part.runs, s.min_points, s.min_length);
    // The returns held in a fit, and the kept runs renumbered to them.
    Ints position(ret.r.size());
    Index held_count = 0;
    for (std::size_t p = 0; p < position.size(); ++p) {
        held_count += part.held[p];
        position[p] = held_count - 1;
    }
    Ints a, b;
    for (std::size_t k = 0; k < keep.size(); ++k) {
        if (!keep[k]) continue;
        a.push_back(position[part.runs.a[k]]);
        b.push_back(position[part.runs.b[k]]);
    }
    Reals held_sigma;
    for (std::size_t p = 0; p < sigma.size(); ++p)
        if (part.held[p]) held_sigma.push_back(sigma[p]);
    ret = kept(ret, part.held);
    if (s.range_sigma == s.range_sigma) held_sigma.assign(ret.r.size(), s.range_sigma);
    Moments moments = prefix_moments(ret.x, ret.y);
    ScanResult result = assemble(ret, TLS, moments, a, b, sensor.angle_min, held_sigma,
                                 {breakpoints, corners, outliers}, n_beams, ring);
    return well_determined(result, s.max_rho_sigma);
}

std::pair<Ints, Ints> partition_optimal_runs(const Reals& x, const Reals& y, const Reals& sigma,
                                             double model_error, const Flags& opens,
                                             double penalty, double clutter_cost,
                                             Index min_points) {
    Sums sums = weighted_sums(x, y, sigma, model_error, Flags(x.size(), true));
    Runs runs = optimal_runs(sums, opens, penalty, clutter_cost, min_points);
    return {runs.a, runs.b};
}

Table partition_stack(const Stack& stack, const PartitionSettings& s) {
    Table table;
    for (Index row = 0; row < stack.rows; ++row)
        table.add(partition_scan(stack.row_ranges(row), stack.row_valid(row), stack, s));
    return table;
}

}  // namespace scanlines
