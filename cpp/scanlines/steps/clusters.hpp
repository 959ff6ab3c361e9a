// Clusters: runs of consecutive returns that belong to one surface
// (scanlines/steps/clusters.py documents the seam of a full circle).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/breakpoints.hpp"

namespace scanlines {

struct ClusterBounds {
    Ints start, end;  // inclusive positions of each cluster
};

// The runs between breaks (flags per pair of positions).
ClusterBounds cluster_bounds(const Flags& breaks);

// Cluster number of every position.
Ints cluster_ids(const Flags& breaks);

struct Clusters {
    Returns returns;  // rotated for a full circle
    Ints start, end;
    Ints breakpoints;  // beams
    bool ring;         // one closed ring
};

// Clusters of one scan's returns, the seam of a full circle joined; known_breaks are the
// break flags of returns if already computed (else empty).
Clusters cluster_returns(Returns returns, Index n_beams, double step, bool full_circle,
                         const BreakpointRule& rule, Index ring_window, Flags known_breaks);

}  // namespace scanlines
