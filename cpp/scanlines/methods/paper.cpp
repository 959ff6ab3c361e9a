#include "scanlines/methods/paper.hpp"

#include <cmath>
#include <utility>

#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/clusters.hpp"
#include "scanlines/steps/corners.hpp"
#include "scanlines/steps/denoise.hpp"
#include "scanlines/steps/events.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"
#include "scanlines/steps/select.hpp"
#include "scanlines/steps/split.hpp"

namespace scanlines {

ScanResult paper_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                      const PaperSettings& s, const Reals& grid) {
    const Index n_beams = ranges.size;
    const double step = sensor.step;
    const bool full_circle = sensor.full_circle;

    // Step 1 (eq. 3): the points, in the sensor frame (y = kx + b depends on the frame).
    Returns returns = valid_returns(ranges, valid, sensor.cos, sensor.sin);
    if (returns.size() == 0) return empty_result({}, {});
    returns = turned(std::move(returns), sensor.angle_min);

    // The range noise: not a threshold of the paper's; the covariances of the segments and
    // the turn window that anchors a closed ring of a full circle take it.
    NoiseLine noise = resolve_noise(sensor.noise, returns, beam_gaps(returns.index, n_beams));
    const double typical = noise_at(noise, median(returns.r));

    // Step 4's rule (eq. 6-7, 21): D = k rho dtheta, no noise term, no line bridge.
    BreakpointRule rule =
        make_rule(ADAPTIVE, s.clustering.k, 0.0, 0.0, 0.0, 0.0, 0.0, {0.0, 0.0});

    // Steps 2-3 (eq. 5, 20): noise points and their neighbours moved to the window mean,
    // the window kept inside the raw clusters. No point is dropped.
    Denoised clean = denoise(std::move(returns), n_beams, step, full_circle, rule, LITERAL,
                             s.clustering.window, 1, 0.0);

    // Step 4: the clusters.
    const Index ring_window =
        full_circle ? turn_window(clean.returns.x, clean.returns.y, clean.returns.index, typical)
                    : 0;
    Clusters clusters = cluster_returns(std::move(clean.returns), n_beams, step, full_circle, rule,
                                        ring_window, std::move(clean.breaks));
    const Returns& ret = clusters.returns;
    const Ints& start = clusters.start;
    const Ints& end = clusters.end;
    const RunCost cost{PAPER, prefix_moments(ret.x, ret.y), {}, {}};  // SSE, square metres

    // Step 5 (eq. 12-13): |Dk| at every position, its peaks the corner candidates.
    Reals scores = slope_scores(ret.r, beam_gaps(ret.index, n_beams), step, start, end, false);
    Ints candidates = peak_positions(scores, start, end);
    Reals candidate_scores(candidates.size());
    for (std::size_t j = 0; j < candidates.size(); ++j) candidate_scores[j] = scores[candidates[j]];

    // Steps 6-7 (eq. 14): every dkth of the grid, the cut with the smallest SSE.
    Levels swept = sweep_levels(cost, start, end, candidates, candidate_scores, grid, true,
                                static_cast<Index>(grid.size()), true);
    Index best = best_level(SSE, swept.sse, swept.segments, swept.levels, ret.size(), 1.0, 0.0)
                     .first;
    Ints corners = level_corners(swept.ranked, swept.accepted, swept.levels[best]);

    // The parts: the corner point shared by both sides; those of min_points returns and
    // min_length kept.
    GroupedRuns parts = cut_at(start, end, corners, true);
    GroupedRuns runs;
    for (std::size_t k = 0; k < parts.a.size(); ++k) {
        Index a = parts.a[k], b = parts.b[k];
        double dx = ret.x[b] - ret.x[a], dy = ret.y[b] - ret.y[a];
        double length = std::sqrt(dx * dx + dy * dy);
        if (b - a + 1 >= s.output.min_points && length >= s.output.min_length) {
            runs.a.push_back(a);
            runs.b.push_back(b);
            runs.group.push_back(parts.group[k]);
        }
    }

    // The corners and jumps between the kept parts (no corner check).
    auto [corner_beams, jumps] = junction_events(ret, PAPER, cost.moments, runs.a, runs.b,
                                                 runs.group, true, clusters.ring, -1.0, {});
    Ints breakpoints = clusters.breakpoints;
    breakpoints.insert(breakpoints.end(), jumps.begin(), jumps.end());
    breakpoints = sorted_distinct(std::move(breakpoints));

    // Step 8 (eq. 15-17, 22): a line per part, five sub-set means and OLS; the covariances
    // from the noise line, or range_sigma where given.
    Reals sigma = return_sigmas(ret.r, noise);
    const double range_sigma = s.output.range_sigma;
    if (range_sigma == range_sigma) sigma.assign(ret.r.size(), range_sigma);
    return assemble(ret, PAPER, cost.moments, runs.a, runs.b, 0.0, sigma,
                    {std::move(breakpoints), std::move(corner_beams), std::move(clean.outliers)},
                    n_beams, full_circle);
}

Table paper_stack(const Stack& stack, const PaperSettings& s, const Reals& grid) {
    return each_row(stack, paper_scan, s, grid);
}

}  // namespace scanlines
