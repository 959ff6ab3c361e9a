#include "scanlines/methods/split_methods.hpp"

#include <cmath>
#include <numeric>

#include "scanlines/methods/clustered.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/merge.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"
#include "scanlines/steps/split.hpp"

namespace scanlines {

namespace {

struct SplitClusters {
    Returns returns;
    Moments moments;
    GroupedRuns runs;
    Clustering clustering;
};

// Steps 1-2 of the split methods: cluster by the rule, split every cluster at the point
// farthest from its chord (or line) while it is farther than split_distance.
SplitClusters cluster_and_split(Returns returns, Index n_beams, const Stack& sensor,
                                const SplitSettings& s) {
    Clusters clusters = cluster_scan(std::move(returns), n_beams, sensor.step, sensor.full_circle,
                                     s.clustering.rule, sensor.noise);
    Moments moments = prefix_moments(clusters.returns.x, clusters.returns.y);
    GroupedRuns whole{clusters.start, clusters.end, Ints(clusters.start.size())};
    std::iota(whole.group.begin(), whole.group.end(), Index{0});
    GroupedRuns runs = split_at_farthest(clusters.returns.x, clusters.returns.y, moments, whole,
                                  s.segments.split_distance, s.segments.split_reference);
    return {std::move(clusters.returns), std::move(moments), std::move(runs),
            {true, clusters.ring, std::move(clusters.breakpoints)}};
}

ScanResult iepf_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                     const SplitSettings& s) {
    const Index n_beams = ranges.size;
    Returns returns = valid_returns(ranges, valid, sensor.cos, sensor.sin);
    if (returns.size() == 0) return empty_result({}, {});
    SplitClusters split = cluster_and_split(std::move(returns), n_beams, sensor, s);
    return finish(split.returns, n_beams, sensor.full_circle, split.moments, split.runs.a,
                  split.runs.b, split.runs.group, split.clustering, {}, sensor.angle_min,
                  s.output, sensor.noise);
}

// Step 1 of split-and-merge: the returns without isolated ones, and the beams of those.
std::pair<Returns, Ints> drop_outliers(Returns returns, double outlier_distance,
                                       double line_distance) {
    const Index n = returns.size();
    if (n < 3) return {std::move(returns), {}};
    const Reals& r = returns.r;
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    Flags outlier(n, false);
    bool any = false;
    for (Index p = 0; p < n; ++p) {
        Index one = p == 0 ? 1 : p - 1;
        Index other = p == 0 ? 2 : (p == n - 1 ? n - 3 : p + 1);
        bool apart = std::fabs(r[p] - r[one]) > outlier_distance &&
                     std::fabs(r[p] - r[other]) > outlier_distance;
        if (!apart) continue;
        double dx = x[other] - x[one], dy = y[other] - y[one];
        double px = x[p] - x[one], py = y[p] - y[one];
        double length = std::hypot(dx, dy);
        double off = length > 0.0 ? std::fabs(px * dy - py * dx) / length : std::hypot(px, py);
        outlier[p] = off > line_distance;
        any = any || outlier[p];
    }
    if (!any) return {std::move(returns), {}};
    Ints dropped;
    Flags keep(n);
    for (Index p = 0; p < n; ++p) {
        keep[p] = !outlier[p];
        if (outlier[p]) dropped.push_back(returns.index[p]);
    }
    return {kept(returns, keep), dropped};
}

ScanResult split_merge_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                            const SplitSettings& s) {
    const Index n_beams = ranges.size;
    Returns all = valid_returns(ranges, valid, sensor.cos, sensor.sin);
    auto [returns, outliers] =
        drop_outliers(std::move(all), s.clustering.outlier_distance, s.segments.split_distance);
    if (returns.size() == 0) return empty_result({}, outliers);
    SplitClusters split = cluster_and_split(std::move(returns), n_beams, sensor, s);
    const Returns& ret = split.returns;
    GroupedRuns runs = split.runs;
    drop_small(ret.x, ret.y, runs.a, runs.b, runs.group, s.output.min_points,
               s.output.min_length);
    Reals sigma =
        covariance_sigmas(s.output.range_sigma, sensor.noise, ret, beam_gaps(ret.index, n_beams));
    runs = merge_by_chi_square(ret, split.moments, runs.a, runs.b, runs.group, sigma,
                               s.segments.merge_chi2, false);
    return finish(ret, n_beams, sensor.full_circle, split.moments, runs.a, runs.b, runs.group,
                  split.clustering, outliers, sensor.angle_min, s.output, sensor.noise);
}

}  // namespace

Table iepf_stack(const Stack& stack, const SplitSettings& s) {
    return each_row(stack, iepf_scan, s);
}

Table split_merge_stack(const Stack& stack, const SplitSettings& s) {
    return each_row(stack, split_merge_scan, s);
}

}  // namespace scanlines
