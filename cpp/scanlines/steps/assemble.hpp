// From runs of positions to the result arrays of an Extraction (scanlines/steps/assemble.py).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/fit.hpp"

namespace scanlines {

// Codes of END_KINDS (scanlines/extraction.py).
enum EndKind : std::int8_t { END_CORNER, END_JUMP, END_OCCLUDED, END_GAP, END_EDGE, END_OPEN };

// What ends each run [a, b] at its start and at its end (breakpoints, corners sorted).
std::vector<std::int8_t> end_kinds(const Returns& returns, const Ints& a, const Ints& b,
                                   Index n_beams, bool wrap, const Ints& breakpoints,
                                   const Ints& corners);

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
