// Breakpoints: where consecutive returns stop belonging to one surface
// (scanlines/steps/breakpoints.py documents the four rules).
#pragma once

#include "scanlines/core.hpp"

namespace scanlines {

enum RuleKind : Index { ADAPTIVE = 0, ABD = 1, PDBS = 2, FIXED = 3 };
constexpr Index NO_RULE = -1;  // cuts at missing beams only

// A clustering rule as a method's parameters give it (noise terms in sigmas, radians).
struct RuleSpec {
    Index breakpoints;
    double k, noise_k, line_k, abd_lambda, pdbs_c0, jump_distance;
};

// A clustering rule with its noise terms in units of the range noise.
struct BreakpointRule {
    Index kind;
    double k, margin_sigmas, tolerance_sigmas;
    NoiseLine noise;
    double abd_lambda, pdbs_c0, jump_distance;
};

BreakpointRule make_rule(Index kind, double k, double noise_k, double line_k, double abd_lambda,
                         double pdbs_c0, double jump_distance, NoiseLine noise);

// The rule of spec, its noise measured from the scan only when the rule uses it.
BreakpointRule scan_rule(const RuleSpec& spec, const Returns& returns, const Ints& gap,
                         NoiseLine noise);

// d_i = |P_{i+1} - P_i| for consecutive points.
Reals neighbour_steps(const Reals& x, const Reals& y);

// Largest distance D between returns r_from and r_to, gap beams apart.
double threshold(const BreakpointRule& rule, double r_from, double r_to, Index gap, double step);

// For each pair of consecutive positions, true where a cluster ends.
Flags break_flags(const Returns& returns, const Ints& gap, double step, const BreakpointRule& rule);

// The breakpoint test between the last and the first position of a full circle.
bool seam_break(const Returns& returns, Index n_beams, double step, const BreakpointRule& rule);

}  // namespace scanlines
