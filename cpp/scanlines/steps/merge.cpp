#include "scanlines/steps/merge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace scanlines {

namespace {
constexpr double INF = std::numeric_limits<double>::infinity();
}

double chi_square(double rho_1, double alpha_1, double rho_2, double alpha_2,
                  const double* covariance_1, const double* covariance_2) {
    auto [d_rho, d_alpha] = hesse_difference(rho_1, alpha_1, rho_2, alpha_2);
    double p = covariance_1[0] + covariance_2[0];
    double q = covariance_1[1] + covariance_2[1];
    double s = covariance_1[3] + covariance_2[3];
    double det = p * s - q * q;
    if (!(det > 0.0)) return NAN;  // degenerate runs carry inf/NaN covariances
    return (s * d_rho * d_rho - 2.0 * q * d_rho * d_alpha + p * d_alpha * d_alpha) / det;
}

GroupedRuns merge_by_chi_square(const Returns& returns, const Moments& moments, const Ints& a_in,
                         const Ints& b_in, const Ints& group_in, const Reals& sigma,
                         double threshold, bool inflate) {
    Ints a = a_in, b = b_in, group = group_in;
    Index m = static_cast<Index>(a.size());
    Lines lines = fit_many(TLS, moments, a, b);
    Reals& rho = lines.rho;
    Reals& alpha = lines.alpha;
    Reals covariance = run_covariances(returns.r, returns.x, returns.y, rho, alpha, a, b, sigma, inflate);
    while (m >= 2) {
        Index best = -1;
        double best_value = INF;
        for (Index k = 0; k < m - 1; ++k) {
            if (group[k] != group[k + 1]) continue;
            double value = chi_square(rho[k], alpha[k], rho[k + 1], alpha[k + 1],
                                      &covariance[4 * k], &covariance[4 * (k + 1)]);
            if (value != value) value = INF;
            if (best < 0 || value < best_value) {
                best = k;
                best_value = value;
            }
        }
        if (best < 0 || !(best_value < threshold)) break;
        b[best] = b[best + 1];
        for (Index k = best + 1; k < m - 1; ++k) {  // delete run best + 1
            a[k] = a[k + 1];
            b[k] = b[k + 1];
            group[k] = group[k + 1];
            rho[k] = rho[k + 1];
            alpha[k] = alpha[k + 1];
            std::copy(&covariance[4 * (k + 1)], &covariance[4 * (k + 1)] + 4, &covariance[4 * k]);
        }
        --m;
        Line line = tls_run(moments, a[best], b[best]);
        rho[best] = line.rho;
        alpha[best] = line.alpha;
        Reals one = run_covariances(returns.r, returns.x, returns.y, {rho[best]}, {alpha[best]},
                                    {a[best]}, {b[best]}, sigma, inflate);
        std::copy(one.begin(), one.end(), &covariance[4 * best]);
    }
    a.resize(m);
    b.resize(m);
    group.resize(m);
    return {a, b, group};
}

}  // namespace scanlines
