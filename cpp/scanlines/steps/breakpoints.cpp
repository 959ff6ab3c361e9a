#include "scanlines/steps/breakpoints.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
constexpr double MAX_STEP_GROWTH = 2.5;

double gap_factor(const BreakpointRule& rule, Index gap, double step) {
    double dphi = static_cast<double>(gap) * step;
    if (rule.kind == ADAPTIVE) return rule.k * dphi;
    if (rule.kind == ABD) {
        double margin = rule.abd_lambda - dphi;
        return margin > 0.0 ? std::sin(dphi) / std::sin(margin) : INF;
    }
    if (rule.kind == PDBS) return std::sqrt(2.0 * (1.0 - std::cos(dphi)));
    return 0.0;
}

double scaled_threshold(const BreakpointRule& rule, double factor, double r_from, double r_to) {
    if (rule.kind == ADAPTIVE || rule.kind == ABD) {
        double margin = rule.margin_sigmas != 0.0 ? rule.margin_sigmas * noise_at(rule.noise, r_from)
                                                  : 0.0;
        return factor * r_from + margin;
    }
    if (rule.kind == PDBS) return rule.pdbs_c0 + factor * std::min(r_from, r_to);
    return rule.jump_distance;
}

// Distance of P from the line through A and B (inf when A == B).
double distance_to_line(double ax, double ay, double bx, double by, double px, double py) {
    double ux = bx - ax, uy = by - ay;
    double length = std::hypot(ux, uy);
    if (length == 0.0) return INF;
    return std::fabs(ux * (py - ay) - uy * (px - ax)) / length;
}

double extrapolation_growth(double t) {
    return std::sqrt((1.0 + t) * (1.0 + t) + t * t) / std::sqrt(5.0);
}

// Pair (p, p+1) continues the line of the pair before and of the pair after.
bool continues_line_at(const Reals& x, const Reals& y, const Ints& gap, const Reals& d, Index p,
                       double tolerance) {
    const Index n = static_cast<Index>(x.size());
    double jump = MAX_STEP_GROWTH * d[p] + tolerance;
    bool has_before = p >= 1 && gap[p - 1] <= MAX_BRIDGED_GAP && d[p - 1] <= jump;
    bool has_after = p + 2 < n && gap[p + 1] <= MAX_BRIDGED_GAP && d[p + 1] <= jump;
    if (!(has_before || has_after)) return false;
    double shorter = INF;
    if (has_before) shorter = d[p - 1];
    if (has_after) shorter = std::min(shorter, d[p + 1]);
    if (!(d[p] <= MAX_STEP_GROWTH * shorter + tolerance && shorter > tolerance)) return false;
    if (has_before) {
        double before = distance_to_line(x[p - 1], y[p - 1], x[p], y[p], x[p + 1], y[p + 1]);
        if (!(before < tolerance * extrapolation_growth(d[p] / d[p - 1]))) return false;
    }
    if (has_after) {
        double after = distance_to_line(x[p + 2], y[p + 2], x[p + 1], y[p + 1], x[p], y[p]);
        if (!(after < tolerance * extrapolation_growth(d[p] / d[p + 1]))) return false;
    }
    return true;
}

}  // namespace

BreakpointRule make_rule(Index kind, double k, double noise_k, double line_k, double abd_lambda,
                         double pdbs_c0, double jump_distance, NoiseLine noise) {
    return {kind,  k,          noise_k * std::sqrt(2.0), line_k * std::sqrt(5.0),
            noise, abd_lambda, pdbs_c0,                  jump_distance};
}

BreakpointRule scan_rule(const RuleSpec& spec, const Returns& returns, const Ints& gap,
                         NoiseLine noise) {
    if (spec.breakpoints == NO_RULE)
        return make_rule(FIXED, spec.k, 0.0, 0.0, spec.abd_lambda, spec.pdbs_c0, INF, {0.0, 0.0});
    bool noisy_rule = (spec.breakpoints == ADAPTIVE || spec.breakpoints == ABD) && spec.noise_k > 0.0;
    if (noisy_rule || spec.line_k > 0.0)
        noise = resolve_noise(noise, returns, gap);
    else
        noise = {0.0, 0.0};
    return make_rule(spec.breakpoints, spec.k, spec.noise_k, spec.line_k, spec.abd_lambda,
                     spec.pdbs_c0, spec.jump_distance, noise);
}

Reals neighbour_steps(const Reals& x, const Reals& y) {
    const Index n = std::max<Index>(static_cast<Index>(x.size()) - 1, 0);
    Reals d(n);
    for (Index p = 0; p < n; ++p) {
        double dx = x[p + 1] - x[p], dy = y[p + 1] - y[p];
        d[p] = std::sqrt(dx * dx + dy * dy);
    }
    return d;
}

double threshold(const BreakpointRule& rule, double r_from, double r_to, Index gap, double step) {
    return scaled_threshold(rule, gap_factor(rule, gap, step), r_from, r_to);
}

Flags break_flags(const Returns& returns, const Ints& gap, double step, const BreakpointRule& rule) {
    const Reals& r = returns.r;
    const Index n = returns.size();
    Flags out(std::max<Index>(n - 1, 0), false);
    if (n < 2) return out;
    Reals d = neighbour_steps(returns.x, returns.y);
    bool line_test = rule.tolerance_sigmas > 0.0;
    double factors[MAX_BRIDGED_GAP + 1];
    for (Index g = 0; g <= MAX_BRIDGED_GAP; ++g) factors[g] = gap_factor(rule, g, step);
    for (Index p = 0; p < n - 1; ++p) {
        if (gap[p] > MAX_BRIDGED_GAP) {
            out[p] = true;
        } else if (!(d[p] < scaled_threshold(rule, factors[gap[p]], r[p], r[p + 1]))) {
            if (line_test) {
                double tolerance = rule.tolerance_sigmas * noise_at(rule.noise, r[p]);
                out[p] = !continues_line_at(returns.x, returns.y, gap, d, p, tolerance);
            } else {
                out[p] = true;
            }
        }
    }
    return out;
}

bool seam_break(const Returns& returns, Index n_beams, double step, const BreakpointRule& rule) {
    const Index last = returns.size() - 1;
    Index gap = returns.index[0] + n_beams - returns.index[last];
    if (gap > MAX_BRIDGED_GAP) return true;
    double d = std::hypot(returns.x[0] - returns.x[last], returns.y[0] - returns.y[last]);
    return !(d < threshold(rule, returns.r[last], returns.r[0], gap, step));
}

}  // namespace scanlines
