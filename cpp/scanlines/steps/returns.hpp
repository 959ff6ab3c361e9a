// The valid returns of a scan, the bundle every step works on (scanlines/steps/returns.py).
#pragma once

#include "scanlines/core.hpp"

namespace scanlines {

// Largest beam gap between consecutive returns that may still be one cluster.
constexpr Index MAX_BRIDGED_GAP = 2;

// Returns of the beams marked valid; cos, sin: bearing tables relative to beam 0.
Returns valid_returns(View<double> ranges, View<bool> valid, View<double> cos, View<double> sin);

// Beams between consecutive positions (a rotated full circle wraps once).
Ints beam_gaps(const Ints& index, Index n_beams);

// The returns with their points turned by angle about the sensor (ranges unchanged).
Returns turned(Returns returns, double angle);

// The returns rotated so that position shift comes first.
Returns rotated(const Returns& returns, Index shift);

// The returns at the positions where keep is true.
Returns kept(const Returns& returns, const Flags& keep);

}  // namespace scanlines
