// Line fitting for runs of points in O(1) from prefix sums (scanlines/steps/fit.py).
#pragma once

#include <utility>

#include "scanlines/core.hpp"

namespace scanlines {

enum Fit : Index { TLS = 0, PAPER = 1 };

// Prefix sums of x, y, xx, xy, yy about the mean point (ox, oy); row-major (5, n + 1).
// Built by prefix_moments (it owns its table) or a view of a caller's table.
class Moments {
public:
    Index stride = 0;  // n + 1
    double ox = 0.0, oy = 0.0;

    Moments() = default;
    Moments(Reals table, Index n_plus_one, double x0, double y0)
        : stride(n_plus_one), ox(x0), oy(y0), storage_(std::move(table)), table_(storage_.data()) {}
    Moments(const double* table, Index n_plus_one, double x0, double y0)
        : stride(n_plus_one), ox(x0), oy(y0), table_(table) {}
    Moments(const Moments& other) { *this = other; }
    Moments& operator=(const Moments& other) {
        stride = other.stride;
        ox = other.ox;
        oy = other.oy;
        storage_ = other.storage_;
        table_ = other.owns() ? storage_.data() : other.table_;
        return *this;
    }
    Moments(Moments&& other) noexcept { *this = std::move(other); }
    Moments& operator=(Moments&& other) noexcept {
        bool owned = other.owns();
        stride = other.stride;
        ox = other.ox;
        oy = other.oy;
        table_ = other.table_;
        storage_ = std::move(other.storage_);
        if (owned) table_ = storage_.data();
        return *this;
    }

    double at(Index row, Index i) const { return table_[row * stride + i]; }
    const Reals& storage() const { return storage_; }
    Reals&& release() { return std::move(storage_); }

private:
    bool owns() const { return !storage_.empty() && table_ == storage_.data(); }
    Reals storage_;
    const double* table_ = nullptr;
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

// Total-least-squares line (rho, alpha, sse) of run [a, b]; NaN for an empty run.
Line tls_run(const Moments& moments, Index a, Index b);

struct Lines {
    Reals rho, alpha, sse;
};
Lines fit_many(Index fit, const Moments& moments, const Ints& a, const Ints& b);

// What the fitting error of a run needs: the fit code, the moments and, for a cost in
// noise units, the running sums of 1 / r^2 and of each return's noise variance (both
// empty for the plain error in square metres).
struct RunCost {
    Index fit;
    Moments moments;
    Reals inv_r2;
    Reals variances;
};

// Floor of run_cost's weight cos^2 of the incidence (72 deg).
constexpr double MIN_INCIDENCE_WEIGHT = 0.1;

// Fitting error of run [a, b]; in noise units when cost.inv_r2 is given.
double run_cost(const RunCost& cost, Index a, Index b);

// (rho_1 - rho_2, alpha_1 - alpha_2) of two Hesse lines, the angle wrapped; of the two
// forms of a line through the origin, the one with the smaller angle difference.
std::pair<double, double> hesse_difference(double rho_1, double alpha_1, double rho_2,
                                           double alpha_2);

// Intersection (x, y) of two Hesse lines; NaN for parallel lines.
std::pair<double, double> line_intersection(double rho_i, double alpha_i, double rho_j,
                                            double alpha_j);

struct Axis {
    double nx, ny, sse, mx, my;
};
// Normal of the TLS line of run [a, b] up to its sign, its error and the run's centroid
// relative to the moments' origin. The run must not be empty.
Axis tls_axis(const Moments& m, Index a, Index b);

// Covariance of (rho, alpha) of each run's line, 4 values (row-major 2 x 2) per run.
// r, x, y: the returns' ranges and points (views: the caller's arrays are not copied).
Reals run_covariances(View<double> r, View<double> x, View<double> y, const Reals& rho,
                      const Reals& alpha, const Ints& a, const Ints& b, View<double> sigma,
                      bool inflate);

}  // namespace scanlines
