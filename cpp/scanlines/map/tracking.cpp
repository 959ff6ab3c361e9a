#include "scanlines/map/tracking.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace scanlines {

namespace {

constexpr Index N = TRACK_STATE;
constexpr double TWO_PI = 6.283185307179586;

double wrap(double angle) { return std::remainder(angle, TWO_PI); }

// Cholesky factor (lower, in place) of the symmetric positive definite a; false if it is not.
bool cholesky(TrackMatrix& a) {
    for (Index j = 0; j < N; ++j) {
        double d = a[j * N + j];
        for (Index k = 0; k < j; ++k) d -= a[j * N + k] * a[j * N + k];
        if (!(d > 0.0) || !std::isfinite(d)) return false;
        d = std::sqrt(d);
        a[j * N + j] = d;
        for (Index i = j + 1; i < N; ++i) {
            double v = a[i * N + j];
            for (Index k = 0; k < j; ++k) v -= a[i * N + k] * a[j * N + k];
            a[i * N + j] = v / d;
        }
        for (Index i = 0; i < j; ++i) a[i * N + j] = 0.0;
    }
    return true;
}

// x solving L L' x = b for the Cholesky factor L.
TrackVector solve(const TrackMatrix& l, TrackVector b) {
    for (Index i = 0; i < N; ++i) {
        for (Index k = 0; k < i; ++k) b[i] -= l[i * N + k] * b[k];
        b[i] /= l[i * N + i];
    }
    for (Index i = N - 1; i >= 0; --i) {
        for (Index k = i + 1; k < N; ++k) b[i] -= l[k * N + i] * b[k];
        b[i] /= l[i * N + i];
    }
    return b;
}

// The inverse of a symmetric positive definite matrix; false if it is not one.
bool inverse(const TrackMatrix& a, TrackMatrix& out) {
    TrackMatrix l = a;
    if (!cholesky(l)) return false;
    for (Index j = 0; j < N; ++j) {
        TrackVector e{};
        e[j] = 1.0;
        TrackVector column = solve(l, e);
        for (Index i = 0; i < N; ++i) out[i * N + j] = column[i];
    }
    for (Index i = 0; i < N; ++i)  // exactly symmetric
        for (Index j = i + 1; j < N; ++j) {
            double m = 0.5 * (out[i * N + j] + out[j * N + i]);
            out[i * N + j] = m;
            out[j * N + i] = m;
        }
    return true;
}

// The prediction: the sensor moved by the odometry increment, corrected by the drift and the
// scale, and carried round the lever; the covariance F C F' + G Q G' plus the random walk of
// drift and scale. The sensor's move in its own frame is (t + (R(turn) - I) l, turn), with t
// the scaled translation, turn the corrected turn and l the lever.
void predict(TrackVector& x, TrackMatrix& c, const double* inc, const TrackParams& p) {
    const double dx = inc[0], dy = inc[1], dt = inc[2];
    const double d = std::hypot(dx, dy);
    const double turn = dt + x[3] * d;
    const double ct = std::cos(turn), st = std::sin(turn);
    const double lx = x[5], ly = x[6];
    const double ix = (1.0 + x[4]) * dx + (ct - 1.0) * lx - st * ly;
    const double iy = (1.0 + x[4]) * dy + st * lx + (ct - 1.0) * ly;
    const double tx = -st * lx - ct * ly, ty = ct * lx - st * ly;  // d(ix, iy) / d(turn)
    const double co = std::cos(x[2]), si = std::sin(x[2]);
    TrackMatrix f{};
    for (Index i = 0; i < N; ++i) f[i * N + i] = 1.0;
    f[0 * N + 2] = -si * ix - co * iy;
    f[1 * N + 2] = co * ix - si * iy;
    f[0 * N + 3] = (co * tx - si * ty) * d;
    f[1 * N + 3] = (si * tx + co * ty) * d;
    f[2 * N + 3] = d;
    f[0 * N + 4] = co * dx - si * dy;
    f[1 * N + 4] = si * dx + co * dy;
    f[0 * N + 5] = co * (ct - 1.0) - si * st;
    f[1 * N + 5] = si * (ct - 1.0) + co * st;
    f[0 * N + 6] = -co * st - si * (ct - 1.0);
    f[1 * N + 6] = -si * st + co * (ct - 1.0);
    x[0] += co * ix - si * iy;
    x[1] += si * ix + co * iy;
    x[2] = wrap(x[2] + turn);
    TrackMatrix fc{}, next{};
    for (Index i = 0; i < N; ++i)
        for (Index j = 0; j < N; ++j) {
            double v = 0.0;
            for (Index k = 0; k < N; ++k) v += f[i * N + k] * c[k * N + j];
            fc[i * N + j] = v;
        }
    for (Index i = 0; i < N; ++i)
        for (Index j = 0; j < N; ++j) {
            double v = 0.0;
            for (Index k = 0; k < N; ++k) v += fc[i * N + k] * f[j * N + k];
            next[i * N + j] = v;
        }
    // G Q G': the increment's noise (x, y isotropic; the turn's also moves the sensor by
    // the lever).
    const double xy = p.odometry_floor + p.odometry_per_metre * d;
    const double th = p.turn_floor + p.turn_per_radian * std::fabs(dt) + p.turn_per_metre * d;
    const double g0 = co * tx - si * ty, g1 = si * tx + co * ty;
    next[0 * N + 0] += xy * xy + g0 * g0 * th * th;
    next[1 * N + 1] += xy * xy + g1 * g1 * th * th;
    next[0 * N + 1] += g0 * g1 * th * th;
    next[1 * N + 0] += g0 * g1 * th * th;
    next[0 * N + 2] += g0 * th * th;
    next[2 * N + 0] += g0 * th * th;
    next[1 * N + 2] += g1 * th * th;
    next[2 * N + 1] += g1 * th * th;
    next[2 * N + 2] += th * th;
    next[3 * N + 3] += p.drift_walk * p.drift_walk * d;
    next[4 * N + 4] += p.scale_walk * p.scale_walk * d;
    c = next;
}

// The unit normals (nx, ny) of each return's local line in the sensor frame; NaN where the
// neighbourhood is too small or not line-like.
void local_normals(View<double> x, View<double> y, const TrackParams& p, Reals& nx, Reals& ny) {
    const Index n = x.size;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    nx.assign(n, nan);
    ny.assign(n, nan);
    const double gap2 = p.neighbour_gap * p.neighbour_gap;
    for (Index k = 0; k < n; ++k) {
        const Index lo = std::max<Index>(0, k - p.normal_window);
        const Index hi = std::min<Index>(n - 1, k + p.normal_window);
        double sx = 0.0, sy = 0.0;
        Index count = 0;
        for (Index j = lo; j <= hi; ++j) {
            const double ex = x[j] - x[k], ey = y[j] - y[k];
            if (ex * ex + ey * ey <= gap2) {
                sx += x[j];
                sy += y[j];
                ++count;
            }
        }
        if (count < 3) continue;
        const double mx = sx / static_cast<double>(count), my = sy / static_cast<double>(count);
        double xx = 0.0, yy = 0.0, xy = 0.0;
        for (Index j = lo; j <= hi; ++j) {
            const double ex = x[j] - x[k], ey = y[j] - y[k];
            if (ex * ex + ey * ey <= gap2) {
                const double u = x[j] - mx, v = y[j] - my;
                xx += u * u;
                yy += v * v;
                xy += u * v;
            }
        }
        const double half = 0.5 * (xx + yy);
        const double disc = std::hypot(0.5 * (xx - yy), xy);
        const double major = half + disc, minor = half - disc;
        if (!(major > 0.0) || minor > p.flatness * p.flatness * major) continue;
        const double angle = 0.5 * std::atan2(2.0 * xy, xx - yy) + 0.5 * 3.141592653589793;
        nx[k] = std::cos(angle);
        ny[k] = std::sin(angle);
    }
}

}  // namespace

TrackStep track_scan(const TrackVector& state, const TrackMatrix& covariance,
                     const double* increment, View<double> px, View<double> py,
                     const LineGrid& grid, const TrackParams& p) {
    TrackStep out{};
    TrackVector xp = state;
    TrackMatrix cp = covariance;
    if (increment) predict(xp, cp, increment, p);
    out.state = xp;
    out.covariance = cp;
    out.predicted = {xp[0], xp[1], xp[2]};
    out.status = TrackStatus::too_few_pairs;
    out.chi_square = 0.0;
    TrackMatrix info{};
    if (!inverse(cp, info)) {
        out.status = TrackStatus::inconsistent;
        return out;
    }

    // The returns: normals from every return, then an even subsample.
    Reals nx, ny;
    local_normals(px, py, p, nx, ny);
    Ints use;
    for (Index k = 0; k < px.size; ++k)
        if (nx[k] == nx[k]) use.push_back(k);
    if (p.max_points > 0 && static_cast<Index>(use.size()) > p.max_points) {
        Ints kept(p.max_points);
        const double span = static_cast<double>(use.size() - 1);
        for (Index k = 0; k < p.max_points; ++k)
            kept[k] = use[static_cast<std::size_t>(
                std::llround(span * static_cast<double>(k) / static_cast<double>(p.max_points - 1)))];
        use.swap(kept);
    }
    const Index m = static_cast<Index>(use.size());

    // The gate of each return from the predicted covariance: position and heading.
    const double a = cp[0], b = cp[1], d = cp[N + 1];
    const double spos2 = std::max(0.0, 0.5 * (a + d) + std::hypot(0.5 * (a - d), b));
    const double sth2 = std::max(0.0, cp[2 * N + 2]);
    Reals gate(m);
    for (Index k = 0; k < m; ++k) {
        const double r2 = px[use[k]] * px[use[k]] + py[use[k]] * py[use[k]];
        const double g = p.gate_base + p.gate_sigmas * std::sqrt(spos2 + r2 * sth2);
        gate[k] = std::min(std::max(g, p.gate_min), p.gate_max);
    }

    const Index lines = grid.rho.size;
    std::vector<Index> per_line(static_cast<std::size_t>(lines), 0);
    Ints line_of(m), touched;
    Reals wx(m), wy(m);
    TrackVector xe = xp;
    double h[9] = {0};
    bool fitted = false;
    for (Index iteration = 0; iteration < p.iterations; ++iteration) {
        const double co = std::cos(xe[2]), si = std::sin(xe[2]);
        for (Index t : touched) per_line[t] = 0;
        touched.clear();
        for (Index k = 0; k < m; ++k) {
            const Index q = use[k];
            wx[k] = xe[0] + co * px[q] - si * py[q];
            wy[k] = xe[1] + si * px[q] + co * py[q];
            const double nwx = co * nx[q] - si * ny[q], nwy = si * nx[q] + co * ny[q];
            line_of[k] = -1;
            const double ci = std::floor((wx[k] - grid.x0) / grid.cell);
            const double cj = std::floor((wy[k] - grid.y0) / grid.cell);
            if (!(ci >= 0.0 && cj >= 0.0 && ci < static_cast<double>(grid.nx) &&
                  cj < static_cast<double>(grid.ny)))
                continue;
            const Index c = static_cast<Index>(ci) * grid.ny + static_cast<Index>(cj);
            double best = gate[k] * gate[k];
            const Index from = std::max<Index>(grid.cell_start[c], 0);
            const Index to = std::min(grid.cell_start[c + 1], grid.cell_lines.size);
            for (Index e = from; e < to; ++e) {
                const Index l = grid.cell_lines[e];
                if (l < 0 || l >= lines) continue;
                const double lnx = std::cos(grid.alpha[l]), lny = std::sin(grid.alpha[l]);
                if (std::fabs(nwx * lnx + nwy * lny) < p.normal_cosine) continue;
                const Index side = lnx * xe[0] + lny * xe[1] > grid.rho[l] ? 1 : 2;
                if ((grid.sides[l] & side) == 0) continue;
                const double sx = grid.start[2 * l], sy = grid.start[2 * l + 1];
                const double abx = grid.end[2 * l] - sx, aby = grid.end[2 * l + 1] - sy;
                const double apx = wx[k] - sx, apy = wy[k] - sy;
                const double len2 = std::max(abx * abx + aby * aby, 1e-18);
                const double t = std::min(std::max((apx * abx + apy * aby) / len2, 0.0), 1.0);
                const double ex = apx - t * abx, ey = apy - t * aby;
                const double dist2 = ex * ex + ey * ey;
                if (dist2 <= best) {
                    best = dist2;
                    line_of[k] = l;
                }
            }
            if (line_of[k] >= 0) {
                if (per_line[line_of[k]]++ == 0) touched.push_back(line_of[k]);
            }
        }
        Index pairs = 0;
        for (Index k = 0; k < m; ++k)
            if (line_of[k] >= 0 && per_line[line_of[k]] >= p.line_returns) ++pairs;
        out.pairs = pairs;
        out.lines = 0;
        for (Index t : touched)
            if (per_line[t] >= p.line_returns) ++out.lines;
        if (pairs < p.min_pairs) {
            fitted = false;
            break;
        }
        double g3[3] = {0, 0, 0};
        std::fill(h, h + 9, 0.0);
        Index weighted = 0;  // pairs whose weight did not vanish (a residual of 1e308 m)
        for (Index k = 0; k < m; ++k) {
            const Index l = line_of[k];
            if (l < 0 || per_line[l] < p.line_returns) continue;
            const double lnx = std::cos(grid.alpha[l]), lny = std::sin(grid.alpha[l]);
            const double e = lnx * wx[k] + lny * wy[k] - grid.rho[l];
            const double jx = lnx, jy = lny;
            const double jt = lny * (wx[k] - xe[0]) - lnx * (wy[k] - xe[1]);
            const double var = p.return_sigma * p.return_sigma +
                               static_cast<double>(per_line[l]) * p.line_sigma * p.line_sigma;
            const double z = std::fabs(e) / std::sqrt(var);
            const double w = (z <= p.huber ? 1.0 : p.huber / z) / var;
            if (!(w > 0.0 && std::isfinite(w * e))) continue;
            ++weighted;
            const double j[3] = {jx, jy, jt};
            for (int r = 0; r < 3; ++r) {
                g3[r] += j[r] * w * e;
                for (int s = 0; s < 3; ++s) h[r * 3 + s] += j[r] * w * j[s];
            }
        }
        if (weighted < p.min_pairs) {  // the map's lines say nothing of this scan
            fitted = false;
            break;
        }
        TrackMatrix system = info;
        for (int r = 0; r < 3; ++r)
            for (int s = 0; s < 3; ++s) system[r * N + s] += h[r * 3 + s];
        TrackVector offset{};
        for (Index i = 0; i < N; ++i) offset[i] = xe[i] - xp[i];
        offset[2] = wrap(offset[2]);
        TrackVector gradient{};
        for (Index i = 0; i < N; ++i) {
            double v = i < 3 ? g3[i] : 0.0;
            for (Index k = 0; k < N; ++k) v += info[i * N + k] * offset[k];
            gradient[i] = v;
        }
        TrackMatrix l = system;
        if (!cholesky(l)) {
            fitted = false;
            out.status = TrackStatus::inconsistent;
            return out;
        }
        TrackVector step = solve(l, gradient);
        double largest = 0.0;
        for (Index i = 0; i < N; ++i) {
            xe[i] -= step[i];
            largest = std::max(largest, std::fabs(step[i]));
        }
        fitted = true;
        if (!(largest >= p.tolerance)) break;
    }
    if (!fitted) return out;
    TrackVector offset{};
    for (Index i = 0; i < N; ++i) offset[i] = xe[i] - xp[i];
    offset[2] = wrap(offset[2]);
    double chi2 = 0.0;
    for (Index i = 0; i < N; ++i)
        for (Index k = 0; k < N; ++k) chi2 += offset[i] * info[i * N + k] * offset[k];
    out.chi_square = chi2;
    if (!(chi2 <= p.max_chi_square)) {
        out.status = TrackStatus::inconsistent;
        return out;
    }
    TrackMatrix system = info;
    for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) system[r * N + s] += h[r * 3 + s];
    TrackMatrix posterior{};
    if (!inverse(system, posterior)) {
        out.status = TrackStatus::inconsistent;
        return out;
    }
    xe[2] = wrap(xe[2]);
    out.state = xe;
    out.covariance = posterior;
    out.status = TrackStatus::aligned;
    return out;
}

}  // namespace scanlines
