// The one linearisation of point-to-line residuals: the filter's update (filter.cpp) and,
// through scanlines._core.point_to_line_system, the registration's and the map tracker's
// steps (scanlines.geometry.registration.point_to_line_system).
#pragma once

#include <cmath>

#include "scanlines/core.hpp"

namespace scanlines {

// The normal equations of a pose update that brings points onto their lines: J' W J (h,
// 3 x 3, row-major), J' W e (g), e' W e (cost) and the pairs whose weight did not vanish.
struct LineSystem {
    double h[9];
    double g[3];
    double cost;
    Index weighted;
};

// Adds one pair. A point p on a line of unit normal (nx, ny) has the residual e = n . p -
// rho; an update (dx, dy, dtheta) turning about a centre c changes it by n . (dx, dy) +
// dtheta (ny lx - nx ly), (lx, ly) = p - c. The pair weighs Huber's weight of e over its
// standard deviation (`huber` of them) over its variance; a weight that is not positive or
// makes a residual of 1e308 m infinite leaves the system as it was.
inline void add_point_to_line(LineSystem& system, double nx, double ny, double lx, double ly,
                              double e, double variance, double huber) {
    const double z = std::fabs(e) / std::sqrt(variance);
    const double w = (z <= huber ? 1.0 : huber / z) / variance;
    if (!(w > 0.0 && std::isfinite(w * e))) return;
    ++system.weighted;
    const double j[3] = {nx, ny, ny * lx - nx * ly};
    system.cost += w * e * e;
    for (int r = 0; r < 3; ++r) {
        system.g[r] += j[r] * w * e;
        for (int s = 0; s < 3; ++s) system.h[r * 3 + s] += j[r] * w * j[s];
    }
}

}  // namespace scanlines
