#include "scanlines/steps/denoise.hpp"

#include <algorithm>
#include <cmath>

#include "scanlines/steps/clusters.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

namespace {

bool any(const Flags& flags) { return std::find(flags.begin(), flags.end(), true) != flags.end(); }

Flags negated(const Flags& flags) {
    Flags out(flags.size());
    for (std::size_t p = 0; p < flags.size(); ++p) out[p] = !flags[p];
    return out;
}

// Mask of the returns (not yet noise) in clusters smaller than least once the noise is
// dropped, and, for least == 2, of the two-return clusters in between.
Flags small_or_in_between(const Returns& returns, const Flags& noise, const Flags& raw_breaks,
                          Index n_beams, double step, bool full_circle,
                          const BreakpointRule& rule, Index least, double margin) {
    Ints kept_positions;
    for (std::size_t p = 0; p < noise.size(); ++p)
        if (!noise[p]) kept_positions.push_back(static_cast<Index>(p));
    Returns kept_returns = kept(returns, negated(noise));
    Ints kept_gap = beam_gaps(kept_returns.index, n_beams);
    bool joined = full_circle && kept_positions.size() >= 3 &&
                  !seam_break(kept_returns, n_beams, step, rule);
    Flags kept_breaks = raw_breaks;
    if (any(noise))  // else the kept returns are all returns: same breaks
        kept_breaks = break_flags(kept_returns, kept_gap, step, rule);
    Flags small = small_clusters(kept_breaks, least, joined);
    if (least == 2) {
        Flags between = in_between_clusters(kept_returns.r, kept_gap, kept_breaks, small, margin);
        for (std::size_t p = 0; p < small.size(); ++p) small[p] = small[p] || between[p];
    }
    Flags out(noise.size(), false);
    for (std::size_t k = 0; k < kept_positions.size(); ++k)
        if (small[k]) out[kept_positions[k]] = true;
    return out;
}

}  // namespace

Flags literal_noise(const Reals& d) {
    const Index n = static_cast<Index>(d.size()) + 1;
    Flags noise(n, false);
    for (Index i = 2; i < n - 2; ++i) noise[i] = d[i - 1] > d[i - 2] && d[i] > d[i + 1];
    return noise;
}

Flags isolated_noise(const Returns& returns, const Ints& gap, double step,
                     const BreakpointRule& rule, const Flags& breaks) {
    const Reals& r = returns.r;
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    const Index n = static_cast<Index>(x.size());
    Flags noise(n, false);
    for (Index i = 1; i < n - 1; ++i) {
        if (!(breaks[i - 1] && breaks[i])) continue;
        Index skip_gap = gap[i - 1] + gap[i];
        if (skip_gap > MAX_BRIDGED_GAP) continue;
        double d_skip = std::hypot(x[i + 1] - x[i - 1], y[i + 1] - y[i - 1]);
        noise[i] = d_skip < threshold(rule, r[i - 1], r[i + 1], skip_gap, step);
    }
    return noise;
}

std::pair<Reals, Reals> window_means(const Reals& x, const Reals& y, const Flags& noise,
                                     Index window, const Flags& breaks) {
    const Index n = static_cast<Index>(x.size());
    Ints ids = cluster_ids(breaks);
    Ints cluster_start(n, 0), cluster_end(n, 0);
    for (Index p = 1; p < n; ++p) cluster_start[p] = ids[p] == ids[p - 1] ? cluster_start[p - 1] : p;
    cluster_end[n - 1] = n - 1;
    for (Index p = n - 2; p >= 0; --p) cluster_end[p] = ids[p] == ids[p + 1] ? cluster_end[p + 1] : p;
    Reals sum_x(n + 1, 0.0), sum_y(n + 1, 0.0);
    for (Index p = 0; p < n; ++p) {
        sum_x[p + 1] = sum_x[p] + x[p];
        sum_y[p + 1] = sum_y[p] + y[p];
    }
    Ints centres;
    for (Index p = 0; p < n; ++p)
        if (noise[p]) centres.push_back(p);
    const Index half = window / 2;  // window >= 1
    Reals mean_x(centres.size()), mean_y(centres.size());
    for (std::size_t j = 0; j < centres.size(); ++j) {
        Index i = centres[j];
        Index lo = std::max(i - half, cluster_start[i]);
        Index hi = std::min(i - half + window - 1, cluster_end[i]);
        double count = static_cast<double>(hi - lo + 1);
        mean_x[j] = (sum_x[hi + 1] - sum_x[lo]) / count;
        mean_y[j] = (sum_y[hi + 1] - sum_y[lo]) / count;
    }
    Reals new_x = x, new_y = y;
    // Left neighbours first, then the points, then right neighbours: where two windows
    // overlap, a point takes the mean of the noise point to its left.
    for (Index offset : {-1, 0, 1}) {
        for (std::size_t j = 0; j < centres.size(); ++j) {
            Index i = centres[j];
            Index target = i + offset;
            if (0 <= target && target < n && ids[target] == ids[i]) {
                new_x[target] = mean_x[j];
                new_y[target] = mean_y[j];
            }
        }
    }
    return {new_x, new_y};
}

Flags small_clusters(const Flags& breaks, Index min_points, bool seam_joined) {
    Ints ids = cluster_ids(breaks);
    Ints sizes(ids.back() + 1, 0);
    for (Index id : ids) ++sizes[id];
    if (seam_joined && sizes.size() > 1) sizes.front() = sizes.back() = sizes.front() + sizes.back();
    Flags out(ids.size());
    for (std::size_t p = 0; p < ids.size(); ++p) out[p] = sizes[ids[p]] < min_points;
    return out;
}

Flags in_between_clusters(const Reals& r, const Ints& gap, const Flags& breaks,
                          const Flags& small, double margin) {
    Flags out(r.size(), false);
    ClusterBounds bounds = cluster_bounds(breaks);
    const Index clusters = static_cast<Index>(bounds.start.size());
    for (Index c = 1; c < clusters - 1; ++c) {
        Index a = bounds.start[c], b = bounds.end[c];
        if (b - a != 1 || small[a] || small[a - 1] || small[b + 1]) continue;
        if (gap[a - 1] > MAX_BRIDGED_GAP || gap[b] > MAX_BRIDGED_GAP) continue;
        double low = std::min(r[a - 1], r[b + 1]) - margin;
        double high = std::max(r[a - 1], r[b + 1]) + margin;
        if (low < r[a] && r[a] < high && low < r[b] && r[b] < high) out[a] = out[b] = true;
    }
    return out;
}

Denoised denoise(Returns returns, Index n_beams, double step, bool full_circle,
                 const BreakpointRule& rule, Index kind, Index window, Index min_cluster_points,
                 double margin) {
    const Index n = returns.size();
    if (kind == NO_DENOISE || n < 3) return {std::move(returns), {}, {}};
    Ints gap = beam_gaps(returns.index, n_beams);
    Flags raw_breaks = break_flags(returns, gap, step, rule);
    if (kind == LITERAL) {
        Reals d(n - 1);
        for (Index p = 0; p < n - 1; ++p)
            d[p] = std::hypot(returns.x[p + 1] - returns.x[p], returns.y[p + 1] - returns.y[p]);
        Flags noise = literal_noise(d);
        if (!any(noise)) return {std::move(returns), {}, std::move(raw_breaks)};
        auto [x, y] = window_means(returns.x, returns.y, noise, window, raw_breaks);
        for (Index p = 0; p < n; ++p) returns.r[p] = std::hypot(x[p], y[p]);
        returns.x = std::move(x);
        returns.y = std::move(y);
        return {std::move(returns), {}, {}};
    }
    Flags noise = isolated_noise(returns, gap, step, rule, raw_breaks);
    if (min_cluster_points > 1) {
        Flags more = small_or_in_between(returns, noise, raw_breaks, n_beams, step, full_circle,
                                         rule, min_cluster_points, margin);
        for (Index p = 0; p < n; ++p) noise[p] = noise[p] || more[p];
    }
    if (!any(noise)) return {std::move(returns), {}, std::move(raw_breaks)};
    Ints outliers;
    for (Index p = 0; p < n; ++p)
        if (noise[p]) outliers.push_back(returns.index[p]);
    return {kept(returns, negated(noise)), std::move(outliers), {}};
}

}  // namespace scanlines
