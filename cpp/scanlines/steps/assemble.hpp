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

// The output settings every method has: the smallest segment reported and the range noise
// of the covariances (NaN: the noise model's).
struct OutputBounds {
    Index min_points;
    double min_length, range_sigma;
};

// What a comparison method keeps and reports: its output bounds and the bounds of the
// corner rule.
struct Output : OutputBounds {
    CornerBounds corners;
};

// Runs with at least min_points points (two at least) and an end-to-end length of
// min_length.
void drop_small(const Reals& x, const Reals& y, Ints& a, Ints& b, Ints& group, Index min_points,
                double min_length);

// The clustering a method's runs came from: whether its breakpoints come from it (else
// they are the jumps between segments), whether the scan is one closed ring, and the
// clustering's breakpoint beams.
struct Clustering {
    bool clustered, ring;
    Ints breakpoints;
};

// Drop small runs, find corners (and breakpoints) and assemble the result arrays.
ScanResult finish(const Returns& returns, Index n_beams, bool full_circle, const Moments& moments,
                  Ints a, Ints b, Ints group, const Clustering& clusters, Ints outliers,
                  double angle_min, const Output& output, NoiseLine noise);

// assemble's output without segments.
ScanResult empty_result(Ints breakpoints, Ints outliers);

}  // namespace scanlines
