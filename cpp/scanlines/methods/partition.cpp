#include "scanlines/methods/partition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "scanlines/methods/penalised.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

namespace {

using namespace penalised;

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
    ScanReturns scan = scan_returns(ranges, valid, sensor, s.noise_sigma);
    if (scan.ret.size() == 0) return empty_result({}, {});
    const Objective objective{s.segments, s.output.min_points, Residual::ALONG_BEAM, false};
    Reals once(scan.ret.r.size(), 1.0);  // every return one observation
    ScanPartition part = ring_partition(scan, once, n_beams, sensor.step, objective);
    Ints every(scan.ret.r.size());  // left-out returns are pieces of their own here
    for (std::size_t p = 0; p < every.size(); ++p) every[p] = static_cast<Index>(p);
    auto [breakpoints, corners] = events(scan.ret, part, scan.sigma, every, sensor.step,
                                         {sensor.full_circle, scan.ring, n_beams});
    Ints kept_ids = kept_runs(scan.ret, part.held, part.runs, s.output.min_points, s.output.min_length);
    HeldRuns held = held_runs(scan, part, kept_ids, s.output.range_sigma);
    Moments moments = prefix_moments(held.ret.x, held.ret.y);
    ScanResult result =
        assemble(held.ret, TLS, moments, held.a, held.b, sensor.angle_min, held.sigma,
                 {breakpoints, corners, left_out(scan.ret, part)}, n_beams, scan.ring);
    return well_determined(result, s.output.max_rho_sigma);
}

std::pair<Ints, Ints> partition_optimal_runs(const Reals& x, const Reals& y, const Reals& sigma,
                                             double model_error, const Flags& opens,
                                             double penalty, double clutter_cost,
                                             Index min_points) {
    Returns ret;
    ret.x = x;
    ret.y = y;
    Sums sums = weighted_sums(ret, sigma, Reals(x.size(), 1.0), model_error, Flags(x.size(), true));
    const Objective objective{{penalty, clutter_cost, model_error}, min_points,
                              Residual::ALONG_BEAM, false};
    Runs runs = optimal_runs(sums, opens, objective, Ints(), Flags());
    return {runs.a, runs.b};
}

Table partition_stack(const Stack& stack, const PartitionSettings& s) {
    return each_row(stack, partition_scan, s);
}

}  // namespace scanlines
