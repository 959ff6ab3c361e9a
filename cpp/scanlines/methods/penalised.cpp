#include "scanlines/methods/penalised.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines::penalised {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
constexpr double PI = 3.141592653589793;
const double GRAZING_ANGLE = 10.0 * (PI / 180.0);  // as math.radians(10.0) rounds
constexpr double CUT_SIGMAS = 5.0;
constexpr double EVENT_SIGMAS = 3.0;
constexpr Index LOOK_BACK = 256;
// The two-stage search: blocks of the first stage, how far around its boundaries the second
// stage looks, and the starts within reach of every end.
constexpr Index COARSE_BLOCK = 4;
constexpr Index BOUNDARY_WINDOW = 16;
constexpr double COARSE_PENALTY = 0.25;  // of the penalty: the first stage over-segments
constexpr Index NEAR_STARTS = 8;
constexpr int ROUNDS = 3;
constexpr int C = Sums::COLUMNS;


double run_cost(const Sums& sums, Index a, Index b, const Objective& o) {
    double held = sums.at(b + 1, 6) - sums.at(a, 6);
    Scatter s = scatter(sums, a, b);
    double chi2 = o.residual == Residual::ACROSS_LINE
                      ? eigenvalues(s.sxx, s.sxy, s.syy).first
                      : along_beam_chi2(s, sums.at(b + 1, 7) - sums.at(a, 7), sums.x0, sums.y0,
                                        o.model_error);
    return 0.5 * chi2 + o.clutter_cost * (static_cast<double>(b - a + 1) - held) + o.penalty;
}

Runs joined_runs(const Sums& sums, const Flags& opens, const Runs& runs, const Objective& o) {
    const std::size_t count = runs.a.size();
    if (count < 2) return runs;
    Runs out = runs;
    std::size_t m = 0;
    for (std::size_t k = 1; k < count; ++k) {
        bool touching = out.b[m] + 1 == runs.a[k] && !opens[runs.a[k]];
        if (touching && run_cost(sums, out.a[m], runs.b[k], o) <=
                            run_cost(sums, out.a[m], out.b[m], o) +
                                run_cost(sums, runs.a[k], runs.b[k], o)) {
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

// Whether each of the returns lo .. lo + count - 1 lies in its run's fit (runs counted from
// lo; returns outside the runs: true).
Flags inside_fit(const Returns& ret, const Sums& sums, const Reals& sigma, double model_error,
                 const Runs& runs, double clutter_cost, Index lo, Index count) {
    Flags out(count, true);
    const double floor = model_error * model_error;
    for (std::size_t k = 0; k < runs.a.size(); ++k) {
        FittedLine line = line_of(sums, runs.a[k], runs.b[k]);
        double c = std::cos(line.alpha), si = std::sin(line.alpha);
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) {
            const Index q = lo + p;
            double off = ret.x[q] * c + ret.y[q] * si - line.rho;
            out[p] = 0.5 * off * off / (sigma[q] * sigma[q] + floor) <= clutter_cost;
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

// Returns outside every run are left out of the next round's sums, so that a run may span
// them at the clutter cost.
void outside_runs_left_out(const Runs& runs, Flags& held) {
    Flags inside(held.size(), false);
    for (std::size_t k = 0; k < runs.a.size(); ++k)
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) inside[p] = true;
    for (std::size_t p = 0; p < held.size(); ++p) held[p] = held[p] && inside[p];
}

}  // namespace

Sums weighted_sums(const Returns& ret, const Reals& sigma, const Reals& footprint,
                   double model_error, const Flags& held) {
    return weighted_sums(ret, sigma, footprint, model_error, held, 0,
                         static_cast<Index>(ret.x.size()));
}

Sums weighted_sums(const Returns& ret, const Reals& sigma, const Reals& footprint,
                   double model_error, const Flags& held, Index lo, Index hi) {
    const Reals& x = ret.x;
    const Reals& y = ret.y;
    const Index n = hi - lo;
    const double x0 = x.empty() ? 0.0 : x[0], y0 = y.empty() ? 0.0 : y[0];
    Sums out{Reals(static_cast<std::size_t>(C * (n + 1)), 0.0), x0, y0};
    const double floor = model_error * model_error;
    double* o = out.v.data();
    for (Index p = lo; p < hi; ++p) {  // row p + 1 - lo: the sums up to return p
        double w = held[p] ? footprint[p] / (sigma[p] * sigma[p] + floor) : 0.0;
        double u = x[p] - x0, v = y[p] - y0;
        const double* prev = o + C * (p - lo);
        double* next = o + C * (p + 1 - lo);
        next[0] = prev[0] + w;
        next[1] = prev[1] + w * u;
        next[2] = prev[2] + w * v;
        next[3] = prev[3] + w * u * u;
        next[4] = prev[4] + w * u * v;
        next[5] = prev[5] + w * v * v;
        next[6] = prev[6] + (held[p] ? 1.0 : 0.0);
        next[7] = prev[7] + (held[p] ? footprint[p] : 0.0);
    }
    return out;
}

Scatter scatter(const Sums& sums, Index a, Index b) {
    double w = sums.at(b + 1, 0) - sums.at(a, 0);
    double mx = (sums.at(b + 1, 1) - sums.at(a, 1)) / w;
    double my = (sums.at(b + 1, 2) - sums.at(a, 2)) / w;
    double sxx = sums.at(b + 1, 3) - sums.at(a, 3) - w * mx * mx;
    double sxy = sums.at(b + 1, 4) - sums.at(a, 4) - w * mx * my;
    double syy = sums.at(b + 1, 5) - sums.at(a, 5) - w * my * my;
    return {w, mx, my, sxx, sxy, syy};
}

std::pair<double, double> eigenvalues(double sxx, double sxy, double syy) {
    double half = 0.5 * (sxx + syy);
    double spread = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
    return {std::max(half - spread, 0.0), half + spread};
}

double along_beam_chi2(const Scatter& s, double footprints, double x0, double y0,
                       double model_error) {
    // Range noise moves a return along its beam: regress the depth along the mean bearing
    // (cx, cy) on the lateral position, so that a short piece of a densely sampled wall
    // cannot turn its line towards the beams to explain the noise. The scatter in that
    // frame, each term scaled by |c|^2 (which cancels from the slope).
    double cx = s.mx + x0, cy = s.my + y0;
    double norm2 = cx * cx + cy * cy;
    if (!(norm2 > 0.0)) return eigenvalues(s.sxx, s.sxy, s.syy).first;
    double depth = cx * cx * s.sxx + 2.0 * cx * cy * s.sxy + cy * cy * s.syy;
    double lateral = cy * cy * s.sxx - 2.0 * cx * cy * s.sxy + cx * cx * s.syy;
    double both = cx * cy * (s.syy - s.sxx) + (cx * cx - cy * cy) * s.sxy;
    if (!(lateral > 0.0)) return std::max(depth / norm2, 0.0);
    // The residual (depth - both^2 / lateral) / norm2, scaled by assumed / (assumed + spread):
    // the weights took each return's variance as sigma^2 + model_error^2 (their mean,
    // `assumed`: the footprints over the weights); the model error lies across the wall,
    // so along the beams it grows by the slope both / lateral: sigma^2 + model_error^2
    // (1 + slope^2). One division for all of it.
    double residual = std::max(depth * lateral - both * both, 0.0);
    double spread = model_error * model_error * s.w * both * both;
    return residual * footprints * lateral /
           (norm2 * (footprints * lateral * lateral + spread));
}

FittedLine line_of(const Sums& sums, Index a, Index b) {
    Scatter s = scatter(sums, a, b);
    double alpha = 0.5 * std::atan2(-2.0 * s.sxy, s.syy - s.sxx);
    double rho = (s.mx + sums.x0) * std::cos(alpha) + (s.my + sums.y0) * std::sin(alpha);
    if (rho < 0.0) {
        rho = -rho;
        alpha = alpha + PI;
    }
    double large = eigenvalues(s.sxx, s.sxy, s.syy).second;
    return {rho, alpha, large > 0.0 ? 1.0 / large : INF, s.w};
}

bool continuous(const Returns& ret, Index p, Index q, Index beams, double step,
                const Reals& sigma, double sigmas) {
    double turn = static_cast<double>(beams) * step;
    if (turn >= GRAZING_ANGLE) return false;
    double reach = std::min(ret.r[p], ret.r[q]) * std::sin(turn) / std::sin(GRAZING_ANGLE - turn);
    double apart = std::hypot(ret.x[q] - ret.x[p], ret.y[q] - ret.y[p]);
    double spread = sigmas * std::sqrt(sigma[p] * sigma[p] + sigma[q] * sigma[q]);
    return apart <= reach + spread;
}

namespace {

// Whether start s is still a candidate at the end of step t: not pruned by then, within the
// look-back, and allowed (expires: as the steps up to t left it).
bool candidate_at(Index s, Index t, const Ints& expires, const Ints& at, const Flags& allowed) {
    const Index span = at.empty() ? t - s : at[t] - at[s];
    if (expires[s] <= t || span > LOOK_BACK) return false;
    return allowed.empty() || allowed[s] || span <= NEAR_STARTS;
}

// The candidates at the end of step from - 1, found again from the pruning the search
// recorded (ascending, as the steps keep them); the prunings recorded after that step undone.
Index candidates_before(Search& search, Index from, const Flags& opens, const Objective& o,
                        const Ints& at, const Flags& allowed, Ints& candidates) {
    const Index n = static_cast<Index>(search.best.size()) - 1;
    for (Index s = 0; s <= n; ++s)  // a start is pruned once, at step expires - min_points
        if (search.expires[s] > n || search.expires[s] - o.min_points >= from)
            search.expires[s] = n + 1;
    Index first = std::max<Index>(from - 2, 0);
    while (first > 0 && !opens[first]) --first;
    Index count = 0;
    for (Index s = first; s < from - 1; ++s)
        if (candidate_at(s, from - 1, search.expires, at, allowed)) candidates[count++] = s;
    return count;
}

}  // namespace

void search_from(const Sums& sums, const Flags& opens, const Objective& o, const Ints& at,
                 const Flags& allowed, Search& search, Index from) {
    const Index n = static_cast<Index>(sums.v.size() / C) - 1;
    if (search.best.size() != static_cast<std::size_t>(n + 1) || from < 1) {
        search = {Reals(n + 1), Ints(n + 1), Ints(n + 1, n + 1)};
        search.best[0] = 0.0;
        from = 1;
    }
    Reals& best = search.best;
    Ints& expires = search.expires;
    Reals cost(n + 1);
    Ints candidates(n + 1);
    Index count = candidates_before(search, from, opens, o, at, allowed, candidates);
    const double* prefix = sums.v.data();
    const bool across = o.residual == Residual::ACROSS_LINE;
    for (Index t = from; t <= n; ++t) {
        if (opens[t - 1]) count = 0;
        candidates[count++] = t - 1;
        // The prefix sums up to t, read once (the same arithmetic as scatter(sums, s, t - 1)).
        double end[C];
        std::copy(prefix + C * t, prefix + C * t + C, end);
        const double left_out = at.empty() ? 1.0 : static_cast<double>(at[t] - at[t - 1]);
        double best_t = best[t - 1] + o.clutter_cost * left_out;
        Index start_t = -1;
        Index kept = 0;
        for (Index c = 0; c < count; ++c) {
            const Index s = candidates[c];
            if (!candidate_at(s, t, expires, at, allowed)) continue;
            const Index span = at.empty() ? t - s : at[t] - at[s];
            candidates[kept] = s;
            double value = INF;
            const double* from_row = prefix + C * s;
            const double held = end[6] - from_row[6];
            if (held >= static_cast<double>(o.min_points)) {
                const double w = end[0] - from_row[0];
                const double mx = (end[1] - from_row[1]) / w;
                const double my = (end[2] - from_row[2]) / w;
                const double sxx = end[3] - from_row[3] - w * mx * mx;
                const double sxy = end[4] - from_row[4] - w * mx * my;
                const double syy = end[5] - from_row[5] - w * my * my;
                double chi2 = across ? eigenvalues(sxx, sxy, syy).first
                                     : along_beam_chi2({w, mx, my, sxx, sxy, syy},
                                                       end[7] - from_row[7], sums.x0, sums.y0,
                                                       o.model_error);
                value = best[s] + 0.5 * chi2;
                value += o.clutter_cost * (static_cast<double>(span) - held);
                if (value + o.penalty < best_t) {
                    best_t = value + o.penalty;
                    start_t = s;
                }
            }
            cost[kept] = value;
            ++kept;
        }
        best[t] = best_t;
        search.start[t] = start_t;
        count = kept;
        for (Index c = 0; c < count; ++c)  // prune the starts that t dominates (PELT)
            if (cost[c] >= best_t && cost[c] < INF && expires[candidates[c]] > n)
                expires[candidates[c]] = t + o.min_points;
    }
}

Runs traced_runs(const Search& search) {
    Runs out;
    Index t = static_cast<Index>(search.start.size()) - 1;
    while (t > 0) {
        if (search.start[t] < 0) {
            --t;
            continue;
        }
        out.a.push_back(search.start[t]);
        out.b.push_back(t - 1);
        t = search.start[t];
    }
    std::reverse(out.a.begin(), out.a.end());
    std::reverse(out.b.begin(), out.b.end());
    return out;
}

Runs optimal_runs(const Sums& sums, const Flags& opens, const Objective& o, const Ints& at,
                  const Flags& allowed) {
    Search search;
    search_from(sums, opens, o, at, allowed, search, 1);
    return traced_runs(search);
}

// The optimum in two stages: the same objective at a quarter of the penalty on blocks of
// COARSE_BLOCK returns (cut also where clusters open), then over every return but with a
// segment longer than NEAR_STARTS starting only within BOUNDARY_WINDOW of a boundary of the
// first stage or where a cluster opens. Row 0 of sums is the scan's return `first`: the
// blocks start at the scan's multiples of COARSE_BLOCK.
Runs two_stage_runs(const Sums& sums, const Flags& opens, const Objective& o, Index first) {
    const Index n = static_cast<Index>(sums.v.size() / C) - 1;
    Ints at;
    for (Index p = 0; p < n; ++p)
        if ((first + p) % COARSE_BLOCK == 0 || opens[p]) at.push_back(p);
    at.push_back(n);
    const Index m = static_cast<Index>(at.size()) - 1;
    Sums coarse{Reals(static_cast<std::size_t>(C * (m + 1))), sums.x0, sums.y0};
    Flags coarse_opens(m);
    for (Index j = 0; j <= m; ++j) {
        std::copy(sums.v.begin() + C * at[j], sums.v.begin() + C * at[j] + C,
                  coarse.v.begin() + C * j);
        if (j < m) coarse_opens[j] = opens[at[j]];
    }
    Objective relaxed = o;
    relaxed.penalty = COARSE_PENALTY * o.penalty;
    Runs blocks = optimal_runs(coarse, coarse_opens, relaxed, at, Flags());
    Flags allowed(n + 1, false);
    auto allow = [&](Index p) {
        for (Index q = std::max<Index>(0, p - BOUNDARY_WINDOW);
             q <= std::min(n, p + BOUNDARY_WINDOW); ++q)
            allowed[q] = true;
    };
    for (std::size_t k = 0; k < blocks.a.size(); ++k) {
        allow(at[blocks.a[k]]);
        allow(at[blocks.b[k] + 1]);
    }
    for (Index p = 0; p < n; ++p)
        if (opens[p]) allowed[p] = true;
    return optimal_runs(sums, opens, o, Ints(), allowed);
}

namespace {

// The runs of one cluster's returns lo .. hi - 1 (counted from lo) and their held flags, in
// up to ROUNDS rounds. No segment crosses an opening, so the optimum is the clusters' optima
// side by side; each cluster is solved alone (its own sums and costs from zero), so that its
// runs depend on its returns only, and a round re-solves only the clusters whose held
// returns changed (a left-out return changes its cluster alone), from the first return that
// changed on (the search before it is the same).
Runs cluster_runs(const Returns& ret, const Reals& sigma, const Reals& footprint, Index lo,
                  Index hi, const Objective& o, Flags& held) {
    const Index count = hi - lo;
    if (count < o.min_points) {  // no segment fits: every return outside the runs
        if (o.bridge_left_out) std::fill(held.begin() + lo, held.begin() + hi, false);
        return {};
    }
    Flags opens(count, false);
    opens[0] = true;
    Runs runs;
    Search search;
    Index from = 1;
    for (int round = 0; round < ROUNDS; ++round) {
        Sums sums = weighted_sums(ret, sigma, footprint, o.model_error, held, lo, hi);
        if (o.two_stage) {
            runs = two_stage_runs(sums, opens, o, lo);
        } else {
            search_from(sums, opens, o, Ints(), Flags(), search, from);
            runs = traced_runs(search);
        }
        // Joined until no two neighbours join: a long wall comes out of the look-back in
        // pieces, and a join of two long pieces can pay where each piece's first did not.
        for (std::size_t before = 0; before != runs.a.size();) {
            before = runs.a.size();
            runs = joined_runs(sums, opens, runs, o);
        }
        Flags fits = inside_fit(ret, sums, sigma, o.model_error, runs, o.clutter_cost, lo, count);
        if (o.bridge_left_out) outside_runs_left_out(runs, fits);
        auto changed = std::mismatch(fits.begin(), fits.end(), held.begin() + lo).first;
        if (changed == fits.end()) break;
        from = static_cast<Index>(changed - fits.begin()) + 1;  // rows up to it are the same
        std::copy(fits.begin(), fits.end(), held.begin() + lo);
    }
    return runs;
}

}  // namespace

ScanPartition best_partition(const Returns& ret, const Reals& sigma, const Reals& footprint,
                         Index n_beams, double step, const Objective& o) {
    const Index n = ret.size();
    Ints gap = beam_gaps(ret.index, n_beams);
    Flags opens(n);
    opens[0] = true;
    for (Index p = 1; p < n; ++p) {
        bool bridged = gap[p - 1] <= MAX_BRIDGED_GAP;
        bool step_ok = continuous(ret, p - 1, p, gap[p - 1], step, sigma, CUT_SIGMAS);
        opens[p] = !(bridged && step_ok);
    }
    if (o.bridge_left_out)  // a lone return off the surface its neighbours share opens nothing
        for (Index p = 1; p + 1 < n; ++p)
            if (opens[p] && opens[p + 1] && gap[p - 1] + gap[p] <= MAX_BRIDGED_GAP + 1 &&
                continuous(ret, p - 1, p + 1, gap[p - 1] + gap[p], step, sigma, CUT_SIGMAS))
                opens[p] = opens[p + 1] = false;
    Flags held(n, true);
    Runs runs;
    for (Index lo = 0; lo < n;) {
        Index hi = lo + 1;
        while (hi < n && !opens[hi]) ++hi;
        Runs found = cluster_runs(ret, sigma, footprint, lo, hi, o, held);
        for (std::size_t k = 0; k < found.a.size(); ++k) {
            runs.a.push_back(lo + found.a[k]);
            runs.b.push_back(lo + found.b[k]);
        }
        lo = hi;
    }
    Sums sums = weighted_sums(ret, sigma, footprint, o.model_error, held);
    runs = trimmed_runs(held, runs);
    std::fill(held.begin(), held.end(), false);  // returns outside the runs are outliers too
    for (std::size_t k = 0; k < runs.a.size(); ++k)
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) held[p] = true;
    Flags fits = inside_fit(ret, sums, sigma, o.model_error, runs, o.clutter_cost, 0, n);
    for (Index p = 0; p < n; ++p) held[p] = held[p] && fits[p];
    runs = trimmed_runs(held, runs);  // a run's end may have left its fit
    return {runs, held, sums, gap};
}

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

Index corner_between(const Returns& ret, const Sums& sums, const Reals& sigma, const Runs& runs,
                     Index i, Index j, double sigmas) {
    const Reals& x = ret.x;
    const Reals& y = ret.y;
    FittedLine li = line_of(sums, runs.a[i], runs.b[i]);
    FittedLine lj = line_of(sums, runs.a[j], runs.b[j]);
    double turn = lj.alpha - li.alpha;
    turn -= PI * std::floor(turn / PI + 0.5);  // undirected: in [-pi/2, pi/2)
    if (std::fabs(turn) <= sigmas * std::sqrt(li.direction_variance + lj.direction_variance))
        return -1;
    double det = std::sin(lj.alpha - li.alpha);
    double cx = (li.rho * std::sin(lj.alpha) - lj.rho * std::sin(li.alpha)) / det;
    double cy = (lj.rho * std::cos(li.alpha) - li.rho * std::cos(lj.alpha)) / det;
    Index end = runs.b[i], begin = runs.a[j];
    double spacing = std::hypot(x[begin] - x[end], y[begin] - y[end]);
    double reach = spacing + sigmas * std::max(sigma[end], sigma[begin]);
    double to_end = std::hypot(cx - x[end], cy - y[end]);
    double to_begin = std::hypot(cx - x[begin], cy - y[begin]);
    if (to_end > reach || to_begin > reach) return -1;
    return to_end <= to_begin ? end : begin;
}

std::pair<Ints, Ints> events(const Returns& ret, const ScanPartition& part, const Reals& sigma,
                             const Ints& positions, double step, ScanShape shape) {
    const Index n = ret.size();
    Ints breakpoints, corners;
    const Index m = static_cast<Index>(positions.size());
    if (m == 0) return {breakpoints, corners};
    Ints owner(n, -1);
    for (std::size_t k = 0; k < part.runs.a.size(); ++k)
        for (Index p = part.runs.a[k]; p <= part.runs.b[k]; ++p) owner[p] = static_cast<Index>(k);
    Ints wide(n + 1, 0);  // beam gaps too wide to bridge, counted up to each position
    for (Index p = 0; p + 1 < n; ++p) wide[p + 1] = wide[p] + (part.gap[p] > MAX_BRIDGED_GAP);
    const Index last = shape.ring ? m : m - 1;
    for (Index k = 0; k < last; ++k) {
        Index p = positions[k], q = positions[(k + 1) % m];
        if (owner[p] >= 0 && owner[p] == owner[q]) continue;
        bool across_gap = q > p && wide[q] > wide[p];
        Index beams = py_mod(ret.index[q] - ret.index[p], shape.n_beams);
        if (across_gap || !continuous(ret, p, q, beams, step, sigma, EVENT_SIGMAS)) {
            breakpoints.push_back(ret.index[p]);
        } else if (owner[p] >= 0 && owner[q] >= 0) {
            Index at = corner_between(ret, part.sums, sigma, part.runs, owner[p], owner[q],
                                      EVENT_SIGMAS);
            if (at >= 0) corners.push_back(ret.index[at]);
        }
    }
    if (shape.full_circle && !shape.ring) breakpoints.push_back(ret.index[positions[m - 1]]);
    std::sort(breakpoints.begin(), breakpoints.end());
    return {breakpoints, corners};
}

Ints kept_runs(const Returns& ret, const Flags& held, const Runs& runs, Index min_points,
                double min_length) {
    Ints keep;
    for (std::size_t k = 0; k < runs.a.size(); ++k) {
        Index count = 0;
        for (Index p = runs.a[k]; p <= runs.b[k]; ++p) count += held[p];
        double length = std::hypot(ret.x[runs.b[k]] - ret.x[runs.a[k]],
                                   ret.y[runs.b[k]] - ret.y[runs.a[k]]);
        if (count >= min_points && length >= min_length) keep.push_back(static_cast<Index>(k));
    }
    return keep;
}

ScanReturns scan_returns(View<double> ranges, View<bool> valid, const Stack& sensor,
                         double noise_sigma) {
    const Index n_beams = ranges.size;
    ScanReturns out{valid_returns(ranges, valid, sensor.cos, sensor.sin), {}, false};
    if (out.ret.size() == 0) return out;
    Ints gap = beam_gaps(out.ret.index, n_beams);
    NoiseLine noise = sensor.noise;
    if (noise_sigma == noise_sigma) noise = {noise_sigma, 0.0};
    noise = resolve_noise(noise, out.ret, gap);
    if (sensor.full_circle) std::tie(out.ret, out.ring) = seam_at_widest_gap(out.ret, gap, n_beams);
    out.sigma.resize(out.ret.r.size());
    for (std::size_t p = 0; p < out.sigma.size(); ++p) out.sigma[p] = noise_at(noise, out.ret.r[p]);
    return out;
}

ScanPartition ring_partition(ScanReturns& scan, Reals& footprint, Index n_beams, double step,
                         const Objective& objective) {
    ScanPartition part = best_partition(scan.ret, scan.sigma, footprint, n_beams, step, objective);
    if (scan.ring && part.runs.a.size() > 1) {
        Index shift = part.runs.b[0] + 1;
        scan.ret = rotated(scan.ret, shift);
        std::rotate(scan.sigma.begin(), scan.sigma.begin() + shift, scan.sigma.end());
        std::rotate(footprint.begin(), footprint.begin() + shift, footprint.end());
        part = best_partition(scan.ret, scan.sigma, footprint, n_beams, step, objective);
    }
    return part;
}

HeldRuns held_runs(const ScanReturns& scan, const ScanPartition& part, const Ints& kept_ids,
                   double range_sigma) {
    Ints position(scan.ret.r.size());
    Index held_count = 0;
    for (std::size_t p = 0; p < position.size(); ++p) {
        held_count += part.held[p];
        position[p] = held_count - 1;
    }
    HeldRuns out;
    for (Index k : kept_ids) {
        out.a.push_back(position[part.runs.a[k]]);
        out.b.push_back(position[part.runs.b[k]]);
    }
    for (std::size_t p = 0; p < scan.sigma.size(); ++p)
        if (part.held[p]) out.sigma.push_back(scan.sigma[p]);
    out.ret = kept(scan.ret, part.held);
    if (range_sigma == range_sigma) out.sigma.assign(out.ret.r.size(), range_sigma);
    return out;
}

Ints left_out(const Returns& ret, const ScanPartition& part) {
    Ints out;
    for (Index p = 0; p < ret.size(); ++p)
        if (!part.held[p]) out.push_back(ret.index[p]);
    return out;
}

}  // namespace scanlines::penalised
