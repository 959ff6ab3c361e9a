// Corner scores and candidate peaks (scanlines/steps/corners.py).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/fit.hpp"

namespace scanlines {

enum CornerScore : Index { TURN = 0, DK = 1, DK_SIGNED = 2 };
constexpr Index MAX_TURN_WINDOW = 15;

// Eq. 13 at every position (0 where a neighbour lies outside the cluster).
Reals slope_scores(const Reals& r, const Ints& gap, double step, const Ints& start,
                   const Ints& end, bool is_signed);

// Absolute turn (radians) between lines fitted to window points on each side.
Reals turn_scores(const Reals& x, const Reals& y, const Moments& moments, const Ints& start,
                  const Ints& end, Index window);

// Points fitted on each side for the turn score, grown with the noise sigma.
Index turn_window(const Reals& x, const Reals& y, const Ints& index, double sigma);

// Positions with |s_i| > |s_{i-1}| and |s_i| > |s_{i+1}| inside a cluster.
Ints peak_positions(const Reals& score, const Ints& start, const Ints& end);

// Position of the largest turn angle of a closed ring, scored cyclically.
Index ring_anchor(const Reals& x, const Reals& y, Index window);

}  // namespace scanlines
