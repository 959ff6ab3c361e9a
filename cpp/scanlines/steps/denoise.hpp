// Denoising before breakpoint detection, Steps 2-3 of the adaptive method
// (scanlines/steps/denoise.py documents the two readings of the noise rule).
#pragma once

#include <utility>

#include "scanlines/core.hpp"
#include "scanlines/steps/breakpoints.hpp"

namespace scanlines {

enum DenoiseKind : Index { ISOLATED = 0, LITERAL = 1, NO_DENOISE = 2 };

// Step 2 as written, on neighbour distances d (length n - 1): a mask of n points.
Flags literal_noise(const Reals& d);

// Points cut off from both neighbours that are themselves continuous (a spike); breaks are
// the break flags of returns.
Flags isolated_noise(const Returns& returns, const Ints& gap, double step,
                     const BreakpointRule& rule, const Flags& breaks);

// Step 3: noise point i and its neighbours become the mean of window points, the window
// clipped to the raw cluster of i (breaks from the raw data): the moved (x, y).
std::pair<Reals, Reals> window_means(const Reals& x, const Reals& y, const Flags& noise,
                                     Index window, const Flags& breaks);

// Mask of the points of clusters with fewer than min_points returns; seam_joined counts
// the first and last clusters of a full circle as one.
Flags small_clusters(const Flags& breaks, Index min_points, bool seam_joined);

// Mask of the returns of two-return clusters that lie in depth between their neighbours
// (within margin), judged only where those are near and not small.
Flags in_between_clusters(const Reals& r, const Ints& gap, const Flags& breaks,
                          const Flags& small, double margin);

// What denoise leaves: the cleaned returns, the beams dropped as noise and the break
// flags of the cleaned returns when known (empty otherwise).
struct Denoised {
    Returns returns;
    Ints outliers;
    Flags breaks;
};

// Steps 2-3 by kind; window is the literal rule's mean-filter window, min_cluster_points
// the smallest cluster the isolated rule keeps, margin the two-return test's allowance.
Denoised denoise(Returns returns, Index n_beams, double step, bool full_circle,
                 const BreakpointRule& rule, Index kind, Index window, Index min_cluster_points,
                 double margin);

}  // namespace scanlines
