#include "scanlines/steps/assemble.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "scanlines/steps/events.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

ScanResult assemble(const Returns& returns, Index fit, const Moments& moments, const Ints& a,
                    const Ints& b, double angle_min, const Reals& sigma, Events events,
                    Index n_beams, bool wrap) {
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    std::sort(events.breakpoints.begin(), events.breakpoints.end());
    std::sort(events.corners.begin(), events.corners.end());
    std::sort(events.outliers.begin(), events.outliers.end());
    Lines fitted = fit_many(fit, moments, a, b);
    Reals covariance = run_covariances(returns, fitted.rho, fitted.alpha, a, b, sigma, true);
    const std::size_t m = a.size();
    Reals lines(LINE_COLUMNS * m);
    const double cos_t = std::cos(angle_min), sin_t = std::sin(angle_min);
    for (std::size_t k = 0; k < m; ++k) {
        double* line = &lines[LINE_COLUMNS * k];
        const double rho = fitted.rho[k];
        const double c = std::cos(fitted.alpha[k]), s = std::sin(fitted.alpha[k]);
        double squares = 0.0;
        for (Index p = a[k]; p <= b[k]; ++p) {
            double off = x[p] * c + y[p] * s - rho;
            squares += off * off;
        }
        line[0] = rho;
        line[1] = wrap_angle(fitted.alpha[k] + angle_min);
        const Index ends[2] = {a[k], b[k]};
        for (int e = 0; e < 2; ++e) {
            Index p = ends[e];
            double off = x[p] * c + y[p] * s - rho;  // foot of the perpendicular onto the line
            double px = x[p] - off * c, py = y[p] - off * s;
            line[2 + 2 * e] = cos_t * px - sin_t * py;
            line[3 + 2 * e] = sin_t * px + cos_t * py;
        }
        line[6] = std::sqrt(squares / static_cast<double>(b[k] - a[k] + 1));
    }
    std::vector<std::int8_t> kinds =
        end_kinds(returns, a, b, n_beams, wrap, events.breakpoints, events.corners);
    std::vector<std::size_t> order(m);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) {
        return returns.index[a[i]] < returns.index[a[j]];
    });
    ScanResult out;
    for (std::size_t k : order) {
        out.first.push_back(returns.index[a[k]]);
        out.last.push_back(returns.index[b[k]]);
        out.n_points.push_back(b[k] - a[k] + 1);
        out.lines.insert(out.lines.end(), &lines[LINE_COLUMNS * k], &lines[LINE_COLUMNS * (k + 1)]);
        out.covariances.insert(out.covariances.end(), &covariance[4 * k], &covariance[4 * k + 4]);
        out.end_kinds.push_back(kinds[2 * k]);
        out.end_kinds.push_back(kinds[2 * k + 1]);
    }
    out.breakpoints = std::move(events.breakpoints);
    out.corners = std::move(events.corners);
    out.outliers = std::move(events.outliers);
    return out;
}

ScanResult empty_result(Ints breakpoints, Ints outliers) {
    ScanResult out;
    std::sort(breakpoints.begin(), breakpoints.end());
    std::sort(outliers.begin(), outliers.end());
    out.breakpoints = std::move(breakpoints);
    out.outliers = std::move(outliers);
    return out;
}

}  // namespace scanlines
