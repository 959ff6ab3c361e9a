#include "scanlines/steps/events.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "scanlines/steps/returns.hpp"
#include "scanlines/steps/split.hpp"

namespace scanlines {

namespace {

// Whether a corner beam lies within one beam of beam (corners sorted).
bool near_corner(const Ints& corners, Index beam) {
    auto at = std::lower_bound(corners.begin(), corners.end(), beam - 1);
    return at != corners.end() && *at <= beam + 1;
}

bool is_listed(const Ints& sorted_beams, Index beam) {
    auto at = std::lower_bound(sorted_beams.begin(), sorted_beams.end(), beam);
    return at != sorted_beams.end() && *at == beam;
}

}  // namespace

std::vector<std::int8_t> end_kinds(const Returns& returns, const Ints& a, const Ints& b,
                                   Index n_beams, bool wrap, const Ints& breakpoints,
                                   const Ints& corners) {
    const Ints& index = returns.index;
    const Reals& r = returns.r;
    const Index n = returns.size();
    std::vector<std::int8_t> out(2 * a.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
        for (int side = 0; side < 2; ++side) {
            Index p = side == 0 ? a[k] : b[k];
            Index step = side == 0 ? -1 : 1;
            Index q = p + step;
            if (wrap) q = py_mod(q, n);
            Index beam = index[p];
            std::int8_t kind;
            if (near_corner(corners, beam)) {
                kind = END_CORNER;
            } else if (q < 0 || q >= n || q == p) {
                kind = END_EDGE;
            } else {
                Index apart = (index[q] - beam) * step;
                if (apart < 0) apart += n_beams;
                Index last_before = side == 1 ? beam : index[q];
                if (apart > MAX_BRIDGED_GAP) {
                    kind = END_GAP;
                } else if (is_listed(breakpoints, last_before)) {
                    kind = r[q] < r[p] ? END_OCCLUDED : END_JUMP;
                } else {
                    kind = END_OPEN;
                }
            }
            out[2 * k + side] = kind;
        }
    }
    return out;
}

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

// Position nearest (cx, cy) among end - reach .. start + reach (within low..high), the
// candidates running on to end + reach + widest (those beyond high count as end).
Index nearest_return(const Reals& x, const Reals& y, double cx, double cy, Index low, Index end,
                     Index start, Index high, Index reach, Index widest) {
    const Index n = static_cast<Index>(x.size());
    if (start < end) high += n;
    Index best = -1;
    double best_distance = INF;
    for (Index offset = -reach; offset < reach + 1 + widest; ++offset) {
        Index candidate = end + offset;
        if (candidate < low || candidate > high) candidate = end;
        candidate = py_mod(candidate, n);
        double distance = std::hypot(x[candidate] - cx, y[candidate] - cy);
        if (distance != distance) distance = INF;
        if (best < 0 || distance < best_distance) {
            best = candidate;
            best_distance = distance;
        }
    }
    return best;
}

}  // namespace

Ints sorted_distinct(Ints values) {
    std::sort(values.begin(), values.end());
    values.erase(std::unique(values.begin(), values.end()), values.end());
    return values;
}

std::pair<Ints, Ints> segment_events(const Returns& returns, Index n_beams, const Moments& moments,
                                     const Ints& a, const Ints& b, const Ints& group,
                                     bool clustered, bool wrap, CornerBounds bounds) {
    const Ints& index = returns.index;
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    const Index m = static_cast<Index>(a.size());
    if (m == 0 || (m == 1 && !wrap)) return {};
    const Index pairs = wrap && m >= 2 ? m : m - 1;
    Ints first;
    Index widest = 0;
    for (Index k = 0; k < pairs; ++k) {
        Index following = (k + 1) % m;
        if (clustered && group[k] != group[following]) continue;
        first.push_back(k);
        Index span = a[following] - b[k];
        widest = std::max(widest, span < 0 ? span + returns.size() : span);
    }
    Lines lines = fit_many(TLS, moments, a, b);
    const Reals& rho = lines.rho;
    const Reals& alpha = lines.alpha;
    Ints corners, jumps;
    for (Index i : first) {
        Index j = (i + 1) % m;
        Index end = b[i], start = a[j];
        double turn = hesse_difference(rho[i], alpha[i], rho[j], alpha[j]).second;
        bool turns = std::fabs(turn) >= bounds.corner_angle;
        auto [cx, cy] = line_intersection(rho[i], alpha[i], rho[j], alpha[j]);
        double to_end = std::hypot(x[end] - cx, y[end] - cy);
        double to_start = std::hypot(x[start] - cx, y[start] - cy);
        bool near = py_mod(index[start] - index[end], std::max<Index>(n_beams, 1)) <= bounds.corner_beams;
        if (near && turns && to_end <= bounds.corner_distance && to_start <= bounds.corner_distance) {
            Index at = nearest_return(x, y, cx, cy, a[i], end, start, b[j], bounds.corner_beams, widest);
            corners.push_back(index[at]);
            continue;
        }
        if (clustered) continue;
        double end_off = line_residual(x, y, end, rho[j], alpha[j]);
        double start_off = line_residual(x, y, start, rho[i], alpha[i]);
        if (!(near && !turns && end_off <= bounds.corner_distance && start_off <= bounds.corner_distance))
            jumps.push_back(index[end]);
    }
    return {sorted_distinct(corners), sorted_distinct(jumps)};
}

std::pair<Ints, Ints> junction_events(const Returns& returns, Index fit, const Moments& moments,
                                      const Ints& a, const Ints& b, const Ints& owner,
                                      bool shared, bool ring, double sigma,
                                      const Reals& turn_sigma) {
    const Ints& index = returns.index;
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    const Index m = static_cast<Index>(a.size());
    Ints corners, jumps;
    for (Index k = 0; k < m; ++k) {
        Index right = k + 1;
        if (right == m) {
            if (!(ring && m >= 2 && a[0] == 0 && b[m - 1] == returns.size() - 1)) break;
            right = 0;
        } else if (owner[k] != owner[right] || a[right] - b[k] > 2) {
            continue;
        }
        Index end = b[k], start = a[right];
        if (shared) {
            corners.push_back(index[start]);
            continue;
        }
        Line li = fit_run(fit, moments, a[k], b[k]);
        Line lj = fit_run(fit, moments, a[right], b[right]);
        auto [cx, cy] = line_intersection(li.rho, li.alpha, lj.rho, lj.alpha);
        double before = std::hypot(x[end] - cx, y[end] - cy);
        double after = std::hypot(x[start] - cx, y[start] - cy);
        Index pick = after < before ? start : end;
        if (sigma >= 0.0) {
            double reach = CORNER_REACH * std::hypot(x[start] - x[end], y[start] - y[end]) + 3.0 * sigma;
            if (!(std::max(before, after) <= reach)) {  // NaN (parallel lines) is not a corner
                jumps.push_back(index[end]);
                continue;
            }
        }
        if (!turn_sigma.empty()) {
            double bound = CORNER_SIGMAS * std::sqrt(turn_sigma[k] * turn_sigma[k] +
                                                     turn_sigma[right] * turn_sigma[right]);
            double turn = hesse_difference(li.rho, li.alpha, lj.rho, lj.alpha).second;
            if (!(std::fabs(turn) >= bound)) continue;  // the noise hides it (or NaN)
        }
        corners.push_back(index[pick]);
    }
    return {corners, jumps};
}

}  // namespace scanlines
