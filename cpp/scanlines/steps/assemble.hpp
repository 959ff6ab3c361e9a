// From runs of positions to the result arrays of an Extraction (scanlines/steps/assemble.py).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/events.hpp"
#include "scanlines/steps/fit.hpp"

namespace scanlines {

// The events of a scan, beams: breakpoints, corners, outliers.
struct Events {
    Ints breakpoints, corners, outliers;
};

// The result arrays: runs [a, b] fitted, in beam order, events sorted; sigma the range
// noise of each return for the covariances; wrap: the last return neighbours the first.
ScanResult assemble(const Returns& returns, Index fit, const Moments& moments, const Ints& a,
                    const Ints& b, double angle_min, const Reals& sigma, Events events,
                    Index n_beams, bool wrap);

// assemble's output without segments.
ScanResult empty_result(Ints breakpoints, Ints outliers);

}  // namespace scanlines
