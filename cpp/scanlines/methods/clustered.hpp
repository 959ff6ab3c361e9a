// The clustering every comparison method starts from (scanlines/methods/base.py).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/clusters.hpp"

namespace scanlines {

// Points fitted on each side of the turn angle that anchors a ring.
constexpr Index RING_WINDOW = 5;

// cluster_returns by the rule of spec, its noise from the scan; NO_RULE makes one cluster
// of every return (a full circle still rotated to start after a gap or at its strongest
// corner).
Clusters cluster_scan(Returns returns, Index n_beams, double step, bool full_circle,
                      const RuleSpec& spec, NoiseLine noise);

}  // namespace scanlines
