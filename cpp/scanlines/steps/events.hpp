// Events between consecutive segments: corners, jumps, and what ends each segment
// (scanlines/steps/events.py documents the rules).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "scanlines/core.hpp"
#include "scanlines/steps/fit.hpp"

namespace scanlines {

// Codes of END_KINDS (scanlines/extraction.py).
enum EndKind : std::int8_t { END_CORNER, END_JUMP, END_OCCLUDED, END_GAP, END_EDGE, END_OPEN };

// A junction's corner lines meet within this many spacings (plus noise) of the facing ends.
constexpr double CORNER_REACH = 2.0;
// Standard deviations of the turn by which two lines must turn to meet at a corner.
constexpr double CORNER_SIGMAS = 3.0;

// The distinct values, ascending.
Ints sorted_distinct(Ints values);

// The bounds of the shared corner rule: beams, metres, radians.
struct CornerBounds {
    Index corner_beams;
    double corner_distance, corner_angle;
};

// Corners and breakpoints (jumps) between consecutive segments [a, b], sorted distinct beams.
std::pair<Ints, Ints> segment_events(const Returns& returns, Index n_beams, const Moments& moments,
                                     const Ints& a, const Ints& b, const Ints& group,
                                     bool clustered, bool wrap, CornerBounds bounds);

// Beams of the corners where two kept segments of one cluster meet, and of jumps.
std::pair<Ints, Ints> junction_events(const Returns& returns, Index fit, const Moments& moments,
                                      const Ints& a, const Ints& b, const Ints& owner,
                                      bool shared, bool ring, double sigma,
                                      const Reals& turn_sigma);

// What ends each run [a, b] at its start and at its end (breakpoints, corners sorted).
std::vector<std::int8_t> end_kinds(const Returns& returns, const Ints& a, const Ints& b,
                                   Index n_beams, bool wrap, const Ints& breakpoints,
                                   const Ints& corners);

}  // namespace scanlines
