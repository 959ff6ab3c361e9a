#include "scanlines/methods/partition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "scanlines/methods/penalised.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

namespace {

using namespace penalised;

constexpr double EVENT_SIGMAS = 3.0;

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
            Index at = corner_between(ret, sums, sigma, runs, owner[p], owner[q], EVENT_SIGMAS);
            if (at >= 0) corners.push_back(ret.index[at]);
        }
    }
    if (shape.full_circle && !shape.ring) breakpoints.push_back(ret.index[n - 1]);
    std::sort(breakpoints.begin(), breakpoints.end());
    return {breakpoints, corners};
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
    const Objective objective{s.penalty, s.clutter_cost, s.model_error, s.min_points,
                              Residual::ALONG_BEAM, false};
    Reals once(ret.r.size(), 1.0);  // every return one observation
    Partition part = best_partition(ret, sigma, once, n_beams, sensor.step, objective);
    if (ring && part.runs.a.size() > 1) {
        // A closed ring: cut it where the first optimum had a boundary, and solve again.
        Index shift = part.runs.b[0] + 1;
        ret = rotated(ret, shift);
        std::rotate(sigma.begin(), sigma.begin() + shift, sigma.end());
        part = best_partition(ret, sigma, once, n_beams, sensor.step, objective);
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
    Returns ret;
    ret.x = x;
    ret.y = y;
    Sums sums = weighted_sums(ret, sigma, Reals(x.size(), 1.0), model_error, Flags(x.size(), true));
    Runs runs = optimal_runs(sums, opens,
                             {penalty, clutter_cost, model_error, min_points, Residual::ALONG_BEAM, false});
    return {runs.a, runs.b};
}

Table partition_stack(const Stack& stack, const PartitionSettings& s) {
    Table table;
    for (Index row = 0; row < stack.rows; ++row)
        table.add(partition_scan(stack.row_ranges(row), stack.row_valid(row), stack, s));
    return table;
}

}  // namespace scanlines
