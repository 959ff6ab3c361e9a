// Line fitting for runs of points in O(1) from prefix sums (scanlines/steps/fit.py).
#pragma once

#include "scanlines/core.hpp"

namespace scanlines {

enum Fit : Index { TLS = 0, PAPER = 1 };

// Prefix sums of x, y, xx, xy, yy about the mean point (ox, oy); row-major (5, n + 1).
struct Moments {
    Reals table;
    Index stride = 0;  // n + 1
    double ox = 0.0, oy = 0.0;
    double at(Index row, Index i) const { return table[row * stride + i]; }
};

struct Line {
    double rho, alpha, sse;
};

Moments prefix_moments(const Reals& x, const Reals& y);

// angle wrapped to (-pi, pi].
inline double wrap_angle(double angle) {
    const double pi = 3.141592653589793;
    return pi - py_mod(pi - angle, 2.0 * pi);
}

struct Normal {
    double nx, ny, rho, sse;
};

// The total-least-squares line of run [a, b] as (cos alpha, sin alpha, rho >= 0, sse).
Normal tls_normal(const Moments& moments, Index a, Index b);

// The line (rho, alpha, sse) of run [a, b] by fit code.
Line fit_run(Index fit, const Moments& moments, Index a, Index b);

// Eq. 15-17 of the paper on the five sub-set means of run [a, b].
Line paper_run(const Moments& moments, Index a, Index b);

struct Lines {
    Reals rho, alpha, sse;
};
Lines fit_many(Index fit, const Moments& moments, const Ints& a, const Ints& b);

// Covariance of (rho, alpha) of each run's line, 4 values (row-major 2 x 2) per run.
Reals run_covariances(const Returns& returns, const Reals& rho, const Reals& alpha, const Ints& a,
                      const Ints& b, const Reals& sigma, bool inflate);

}  // namespace scanlines
