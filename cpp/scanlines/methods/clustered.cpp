#include "scanlines/methods/clustered.hpp"

#include "scanlines/steps/returns.hpp"

namespace scanlines {

Clusters cluster_scan(Returns returns, Index n_beams, double step, bool full_circle,
                      const RuleSpec& spec, NoiseLine noise) {
    BreakpointRule rule = scan_rule(spec, returns, beam_gaps(returns.index, n_beams), noise);
    Clusters out = cluster_returns(std::move(returns), n_beams, step, full_circle, rule,
                                   RING_WINDOW, {});
    if (spec.breakpoints == NO_RULE) {
        out.start = {0};
        out.end = {out.returns.size() - 1};
        out.breakpoints.clear();
    }
    return out;
}

}  // namespace scanlines
