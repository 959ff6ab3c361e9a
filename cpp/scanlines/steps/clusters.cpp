#include "scanlines/steps/clusters.hpp"

#include <algorithm>

#include "scanlines/steps/corners.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

ClusterBounds cluster_bounds(const Flags& breaks) {
    const Index n = static_cast<Index>(breaks.size()) + 1;
    ClusterBounds out;
    out.start.push_back(0);
    for (Index p = 0; p < n - 1; ++p)
        if (breaks[p]) {
            out.end.push_back(p);
            out.start.push_back(p + 1);
        }
    out.end.push_back(n - 1);
    return out;
}

Ints cluster_ids(const Flags& breaks) {
    Ints ids(breaks.size() + 1, 0);
    for (std::size_t p = 0; p < breaks.size(); ++p) ids[p + 1] = ids[p] + breaks[p];
    return ids;
}

namespace {

// Breakpoint beams: the last beam of each cluster but the last (it too when at_seam).
Ints break_beams(const Ints& index, const Ints& end, bool at_seam) {
    std::size_t count = at_seam ? end.size() : end.size() - 1;
    Ints out;
    for (std::size_t c = 0; c < count; ++c) out.push_back(index[end[c]]);
    std::sort(out.begin(), out.end());
    return out;
}

struct SeamRotation {
    Index rotate_to;
    bool seam_is_break, ring;
};

SeamRotation seam_rotation(const Returns& returns, const Ints& gap, Index n_beams, double step,
                           const BreakpointRule& rule) {
    if (seam_break(returns, n_beams, step, rule)) return {0, true, false};
    Flags breaks = break_flags(returns, gap, step, rule);
    for (std::size_t p = 0; p < breaks.size(); ++p)
        if (breaks[p]) return {static_cast<Index>(p) + 1, true, false};
    return {0, false, true};
}

}  // namespace

Clusters cluster_returns(Returns returns, Index n_beams, double step, bool full_circle,
                         const BreakpointRule& rule, Index ring_window, Flags known_breaks) {
    const Index n = returns.size();
    if (n == 0) return {std::move(returns), {}, {}, {}, false};
    bool ring = false, at_seam = false;
    if (full_circle && n >= 3) {
        SeamRotation seam =
            seam_rotation(returns, beam_gaps(returns.index, n_beams), n_beams, step, rule);
        at_seam = seam.seam_is_break;
        ring = seam.ring;
        Index shift = seam.rotate_to;
        if (ring) shift = ring_anchor(returns.x, returns.y, ring_window);
        if (shift) returns = rotated(returns, shift);
        known_breaks.clear();
    }
    if (ring) return {std::move(returns), {0}, {n - 1}, {}, true};
    Flags breaks = std::move(known_breaks);
    if (static_cast<Index>(breaks.size()) != n - 1)
        breaks = break_flags(returns, beam_gaps(returns.index, n_beams), step, rule);
    ClusterBounds bounds = cluster_bounds(breaks);
    Ints beams = break_beams(returns.index, bounds.end, at_seam);
    return {std::move(returns), bounds.start, bounds.end, beams, false};
}

}  // namespace scanlines
