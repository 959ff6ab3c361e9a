#include "scanlines/steps/fit.hpp"

#include <algorithm>
#include <cmath>

namespace scanlines {

namespace {
constexpr double PI = 3.141592653589793;
constexpr Index PAPER_SUBSETS = 5;

}  // namespace

Axis tls_axis(const Moments& m, Index a, Index b) {
    double n = static_cast<double>(b + 1 - a);
    double sx = m.at(0, b + 1) - m.at(0, a);
    double sy = m.at(1, b + 1) - m.at(1, a);
    double mx = sx / n, my = sy / n;
    double cxx = m.at(2, b + 1) - m.at(2, a) - sx * mx;
    double cxy = m.at(3, b + 1) - m.at(3, a) - sx * my;
    double cyy = m.at(4, b + 1) - m.at(4, a) - sy * my;
    double spread = cyy - cxx;
    double h = std::sqrt(spread * spread + 4.0 * cxy * cxy);
    double sse = std::max(0.5 * (cxx + cyy) - 0.5 * h, 0.0);
    double nx = 1.0, ny = 0.0;
    if (h > 0.0) {
        nx = std::sqrt(std::max(0.5 * (1.0 + spread / h), 0.0));
        ny = std::copysign(std::sqrt(std::max(0.5 * (1.0 - spread / h), 0.0)), -cxy);
    }
    return {nx, ny, sse, mx, my};
}

namespace {
// Normalise to rho >= 0 and alpha in (-pi, pi]: (alpha, rho).
void hesse(double& alpha, double& rho) {
    if (rho < 0.0) {
        rho = -rho;
        alpha = alpha + PI;
    }
    alpha = wrap_angle(alpha);
}
}  // namespace

Moments prefix_moments(const Reals& x, const Reals& y) {
    const Index n = static_cast<Index>(x.size());
    double ox = 0.0, oy = 0.0;
    for (Index i = 0; i < n; ++i) {
        ox += x[i];
        oy += y[i];
    }
    if (n) {
        ox /= static_cast<double>(n);
        oy /= static_cast<double>(n);
    }
    const Index s = n + 1;
    Reals table(static_cast<std::size_t>(5 * s), 0.0);
    double* t = table.data();
    for (Index i = 0; i < n; ++i) {
        double u = x[i] - ox;
        double v = y[i] - oy;
        t[i + 1] = t[i] + u;
        t[s + i + 1] = t[s + i] + v;
        t[2 * s + i + 1] = t[2 * s + i] + u * u;
        t[3 * s + i + 1] = t[3 * s + i] + u * v;
        t[4 * s + i + 1] = t[4 * s + i] + v * v;
    }
    return Moments(std::move(table), s, ox, oy);
}

Normal tls_normal(const Moments& moments, Index a, Index b) {
    if (b < a) return {NAN, NAN, NAN, NAN};
    Axis axis = tls_axis(moments, a, b);
    double rho = (axis.mx + moments.ox) * axis.nx + (axis.my + moments.oy) * axis.ny;
    if (rho < 0.0) return {-axis.nx, -axis.ny, -rho, axis.sse};
    return {axis.nx, axis.ny, rho, axis.sse};
}

Line paper_run(const Moments& moments, Index a, Index b) {
    const Index n = b + 1 - a;
    if (n <= 0) return {NAN, NAN, NAN};
    const Index parts = std::min(n, PAPER_SUBSETS);
    double m = 0.0, sum_x = 0.0, sum_y = 0.0, sum_xx = 0.0, sum_xy = 0.0, sum_yy = 0.0;
    for (Index j = 0; j < parts; ++j) {
        Index lo = std::min(a + (j * n) / parts, a + n);
        Index hi = std::min(a + ((j + 1) * n) / parts, a + n);
        if (hi <= lo) continue;
        double count = static_cast<double>(hi - lo);
        double mean_x = (moments.at(0, hi) - moments.at(0, lo)) / count;
        double mean_y = (moments.at(1, hi) - moments.at(1, lo)) / count;
        m += 1.0;
        sum_x += mean_x;
        sum_y += mean_y;
        sum_xx += mean_x * mean_x;
        sum_xy += mean_x * mean_y;
        sum_yy += mean_y * mean_y;
    }
    double denominator = m * sum_xx - sum_x * sum_x;
    if (denominator <= 1e-18 * (m * sum_yy - sum_y * sum_y)) return {NAN, NAN, NAN};
    double k = (m * sum_xy - sum_x * sum_y) / denominator;
    double intercept = (sum_xx * sum_y - sum_x * sum_xy) / denominator;
    double sx = moments.at(0, b + 1) - moments.at(0, a);
    double sy = moments.at(1, b + 1) - moments.at(1, a);
    double sxx = moments.at(2, b + 1) - moments.at(2, a);
    double sxy = moments.at(3, b + 1) - moments.at(3, a);
    double syy = moments.at(4, b + 1) - moments.at(4, a);
    double sse = syy - 2 * k * sxy - 2 * intercept * sy + k * k * sxx + 2 * k * intercept * sx;
    sse = std::max(sse + static_cast<double>(n) * intercept * intercept, 0.0);
    double norm = std::hypot(k, 1.0);
    double alpha = std::atan2(1.0 / norm, -k / norm);
    double rho = (intercept + moments.oy - k * moments.ox) / norm;
    hesse(alpha, rho);
    return {rho, alpha, sse};
}

Line tls_run(const Moments& moments, Index a, Index b) {
    Normal normal = tls_normal(moments, a, b);
    return {normal.rho, std::atan2(normal.ny, normal.nx), normal.sse};
}

Line fit_run(Index fit, const Moments& moments, Index a, Index b) {
    if (fit == PAPER) return paper_run(moments, a, b);
    return tls_run(moments, a, b);
}

Lines fit_many(Index fit, const Moments& moments, const Ints& a, const Ints& b) {
    const std::size_t count = a.size();
    Lines out{Reals(count), Reals(count), Reals(count)};
    for (std::size_t k = 0; k < count; ++k) {
        Line line = fit_run(fit, moments, a[k], b[k]);
        out.rho[k] = line.rho;
        out.alpha[k] = line.alpha;
        out.sse[k] = line.sse;
    }
    return out;
}

double run_cost(const RunCost& cost, Index a, Index b) {
    double rho, sse;
    if (cost.fit == PAPER) {
        Line line = paper_run(cost.moments, a, b);
        rho = line.rho;
        sse = line.sse;
    } else {
        Normal normal = tls_normal(cost.moments, a, b);
        rho = normal.rho;
        sse = normal.sse;
    }
    const Reals& inv_r2 = cost.inv_r2;
    if (inv_r2.empty() || b < a) return sse;
    double count = static_cast<double>(b - a + 1);
    double mean_inv_r2 = (inv_r2[b + 1] - inv_r2[a]) / count;
    double weight = rho * rho * mean_inv_r2;
    if (weight != weight) return sse;  // NaN line: the cost stays NaN
    double variance = (cost.variances[b + 1] - cost.variances[a]) / count;
    return sse / (std::min(std::max(weight, MIN_INCIDENCE_WEIGHT), 1.0) * variance);
}

std::pair<double, double> hesse_difference(double rho_1, double alpha_1, double rho_2,
                                           double alpha_2) {
    double direct = wrap_angle(alpha_1 - alpha_2);
    double flipped = wrap_angle(alpha_1 - alpha_2 + PI);
    if (std::fabs(flipped) < std::fabs(direct)) return {rho_1 + rho_2, flipped};
    return {rho_1 - rho_2, direct};
}

std::pair<double, double> line_intersection(double rho_i, double alpha_i, double rho_j,
                                            double alpha_j) {
    double det = std::sin(alpha_j - alpha_i);
    if (!(std::fabs(det) > 1e-12)) return {NAN, NAN};
    double x = (rho_i * std::sin(alpha_j) - rho_j * std::sin(alpha_i)) / det;
    double y = (rho_j * std::cos(alpha_i) - rho_i * std::cos(alpha_j)) / det;
    return {x, y};
}

Reals run_covariances(View<double> r, View<double> x, View<double> y, const Reals& rho,
                      const Reals& alpha, const Ints& a, const Ints& b, View<double> sigma,
                      bool inflate) {
    const std::size_t runs = rho.size();
    Reals cos_a(runs), sin_a(runs), count(runs, 0.0), along_sum(runs, 0.0), t0(runs);
    for (std::size_t k = 0; k < runs; ++k) {
        cos_a[k] = std::cos(alpha[k]);
        sin_a[k] = std::sin(alpha[k]);
    }
    for (std::size_t k = 0; k < runs; ++k)
        for (Index p = a[k]; p <= b[k]; ++p) {
            count[k] += 1.0;
            along_sum[k] += -x[p] * sin_a[k] + y[p] * cos_a[k];
        }
    for (std::size_t k = 0; k < runs; ++k) t0[k] = along_sum[k] / std::max(count[k], 1.0);
    Reals s2(runs, 0.0), s2_var(runs, 0.0), s_var(runs, 0.0), var_sum(runs, 0.0), chi2(runs, 0.0);
    for (std::size_t k = 0; k < runs; ++k)
        for (Index p = a[k]; p <= b[k]; ++p) {
            double s = -x[p] * sin_a[k] + y[p] * cos_a[k] - t0[k];
            double scaled = sigma[p] * rho[k] / r[p];
            double var = scaled * scaled;
            double off = x[p] * cos_a[k] + y[p] * sin_a[k] - rho[k];
            s2[k] += s * s;
            s2_var[k] += s * s * var;
            s_var[k] += s * var;
            var_sum[k] += var;
            chi2[k] += var > 0.0 ? off * off / var : 0.0;
        }
    Reals out(4 * runs);
    for (std::size_t k = 0; k < runs; ++k) {
        double scale = 1.0;
        if (inflate && count[k] > 2.0) scale = std::max(chi2[k] / (count[k] - 2.0), 1.0);
        double var_alpha = s2_var[k] / (s2[k] * s2[k]);
        double var_mean = var_sum[k] / (count[k] * count[k]);
        double cov_mean_alpha = -s_var[k] / (count[k] * s2[k]);
        out[4 * k] = scale * (var_mean + t0[k] * t0[k] * var_alpha + 2.0 * t0[k] * cov_mean_alpha);
        out[4 * k + 1] = out[4 * k + 2] = scale * (cov_mean_alpha + t0[k] * var_alpha);
        out[4 * k + 3] = scale * var_alpha;
    }
    return out;
}

}  // namespace scanlines
