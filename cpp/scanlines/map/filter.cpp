#include "scanlines/map/filter.hpp"

#include "scanlines/map/point_to_line.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace scanlines {

namespace {

constexpr Index N = FILTER_STATE;
constexpr double TWO_PI = 6.283185307179586;

double wrap(double angle) { return std::remainder(angle, TWO_PI); }

// Cholesky factor (lower, in place) of the symmetric positive definite a; false if it is not.
bool cholesky(FilterMatrix& a) {
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
FilterVector solve(const FilterMatrix& l, FilterVector b) {
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
bool inverse(const FilterMatrix& a, FilterMatrix& out) {
    FilterMatrix l = a;
    if (!cholesky(l)) return false;
    for (Index j = 0; j < N; ++j) {
        FilterVector e{};
        e[j] = 1.0;
        FilterVector column = solve(l, e);
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
void predict(FilterVector& x, FilterMatrix& c, const double* inc, const FilterParams& p) {
    const double dx = inc[0], dy = inc[1], dt = inc[2];
    const double d = std::hypot(dx, dy);
    const double turn = dt + x[3] * d;
    const double ct = std::cos(turn), st = std::sin(turn);
    const double lx = x[5], ly = x[6];
    const double ix = (1.0 + x[4]) * dx + (ct - 1.0) * lx - st * ly;
    const double iy = (1.0 + x[4]) * dy + st * lx + (ct - 1.0) * ly;
    const double tx = -st * lx - ct * ly, ty = ct * lx - st * ly;  // d(ix, iy) / d(turn)
    const double co = std::cos(x[2]), si = std::sin(x[2]);
    FilterMatrix f{};
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
    FilterMatrix fc{}, next{};
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
void local_normals(View<double> x, View<double> y, const FilterParams& p, Reals& nx, Reals& ny) {
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

// The returns a scan is matched with: every return's local line (its normal, sensor frame;
// NaN: none), the positions `use` of those with one (evenly subsampled to max_points) and
// each used return's gate (metres).
struct ScanReturns {
    View<double> x, y;
    Reals nx, ny;
    Ints use;
    Reals gate;
    Index size() const { return static_cast<Index>(use.size()); }
};

// The returns of a scan (x, y: sensor frame, beam order), gated by the predicted covariance
// cp: position and heading.
ScanReturns scan_returns(View<double> px, View<double> py, const FilterMatrix& cp,
                         const FilterParams& p) {
    ScanReturns r{px, py, {}, {}, {}, {}};
    local_normals(px, py, p, r.nx, r.ny);
    for (Index k = 0; k < px.size; ++k)
        if (r.nx[k] == r.nx[k]) r.use.push_back(k);
    if (p.max_points > 0 && r.size() > p.max_points) {
        Ints kept(p.max_points);
        const double span = static_cast<double>(r.use.size() - 1);
        for (Index k = 0; k < p.max_points; ++k) {
            // One return: the first (numpy's linspace), not 0 / 0.
            const double at = p.max_points > 1 ? span * static_cast<double>(k) /
                                                     static_cast<double>(p.max_points - 1)
                                               : 0.0;
            kept[k] = r.use[static_cast<std::size_t>(std::llround(at))];
        }
        r.use.swap(kept);
    }
    const double a = cp[0], b = cp[1], d = cp[N + 1];
    const double spos2 = std::max(0.0, 0.5 * (a + d) + std::hypot(0.5 * (a - d), b));
    const double sth2 = std::max(0.0, cp[2 * N + 2]);
    r.gate.resize(r.use.size());
    for (Index k = 0; k < r.size(); ++k) {
        const Index q = r.use[k];
        const double r2 = px[q] * px[q] + py[q] * py[q];
        const double g = p.gate_base + p.gate_sigmas * std::sqrt(spos2 + r2 * sth2);
        r.gate[k] = std::min(std::max(g, p.gate_min), p.gate_max);
    }
    return r;
}

// The map line nearest the world point (wx, wy) within `gate` that runs the way of the
// return's local line (normal nwx, nwy: world frame) and was seen from the side of the
// estimate's position xe; -1: none. Cell and line ids out of range are skipped.
Index nearest_line(double wx, double wy, double nwx, double nwy, double gate,
                   const FilterVector& xe, const LineGrid& grid, const FilterParams& p) {
    const CellGrid& cells = gate <= grid.near_reach ? grid.near : grid.wide;
    const double ci = std::floor((wx - cells.x0) / cells.cell);
    const double cj = std::floor((wy - cells.y0) / cells.cell);
    if (!(ci >= 0.0 && cj >= 0.0 && ci < static_cast<double>(cells.nx) &&
          cj < static_cast<double>(cells.ny)))
        return -1;
    const Index c = static_cast<Index>(ci) * cells.ny + static_cast<Index>(cj);
    const Index lines = grid.rho.size;
    const Index from = std::max<Index>(cells.cell_start[c], 0);
    const Index to = std::min(cells.cell_start[c + 1], cells.cell_lines.size);
    double best = gate * gate;
    Index found = -1;
    for (Index e = from; e < to; ++e) {
        const Index l = cells.cell_lines[e];
        if (l < 0 || l >= lines) continue;
        const double lnx = grid.normal[2 * l], lny = grid.normal[2 * l + 1];
        if (std::fabs(nwx * lnx + nwy * lny) < p.normal_cosine) continue;
        const Index side = lnx * xe[0] + lny * xe[1] > grid.rho[l] ? 1 : 2;
        if ((grid.sides[l] & side) == 0) continue;
        const double sx = grid.start[2 * l], sy = grid.start[2 * l + 1];
        const double abx = grid.end[2 * l] - sx, aby = grid.end[2 * l + 1] - sy;
        const double apx = wx - sx, apy = wy - sy;
        const double len2 = std::max(abx * abx + aby * aby, 1e-18);
        const double t = std::min(std::max((apx * abx + apy * aby) / len2, 0.0), 1.0);
        const double ex = apx - t * abx, ey = apy - t * aby;
        const double dist2 = ex * ex + ey * ey;
        if (dist2 <= best) {
            best = dist2;
            found = l;
        }
    }
    return found;
}

// The returns matched to the map at an estimate: each used return's world position and map
// line (-1: none), the returns on each line (zero but on the `touched` lines), the returns
// on lines met by at least line_returns of them (`pairs`) and those lines (`lines`).
struct Association {
    Reals wx, wy;
    Ints line_of;
    Ints per_line;
    Ints touched;
    Index pairs = 0, lines = 0;
};

// The association step: the returns moved to the world by the estimate xe, each matched to
// its nearest map line (nearest_line).
void associate(const FilterVector& xe, const ScanReturns& r, const LineGrid& grid,
               const FilterParams& p, Association& a) {
    const double co = std::cos(xe[2]), si = std::sin(xe[2]);
    for (Index t : a.touched) a.per_line[t] = 0;
    a.touched.clear();
    for (Index k = 0; k < r.size(); ++k) {
        const Index q = r.use[k];
        a.wx[k] = xe[0] + co * r.x[q] - si * r.y[q];
        a.wy[k] = xe[1] + si * r.x[q] + co * r.y[q];
        const double nwx = co * r.nx[q] - si * r.ny[q], nwy = si * r.nx[q] + co * r.ny[q];
        const Index l = nearest_line(a.wx[k], a.wy[k], nwx, nwy, r.gate[k], xe, grid, p);
        a.line_of[k] = l;
        if (l >= 0 && a.per_line[l]++ == 0) a.touched.push_back(l);
    }
    a.pairs = 0;
    for (Index k = 0; k < r.size(); ++k)
        if (a.line_of[k] >= 0 && a.per_line[a.line_of[k]] >= p.line_returns) ++a.pairs;
    a.lines = 0;
    for (Index t : a.touched)
        if (a.per_line[t] >= p.line_returns) ++a.lines;
}

// The normal equations of the matched returns on their lines (point_to_line.hpp), each
// pair's variance its return's own and its line's, shared by the returns on it.
LineSystem point_to_line_system(const FilterVector& xe, const Association& a,
                                const LineGrid& grid, const FilterParams& p) {
    LineSystem out{};
    for (std::size_t k = 0; k < a.line_of.size(); ++k) {
        const Index l = a.line_of[k];
        if (l < 0 || a.per_line[l] < p.line_returns) continue;
        const double lnx = grid.normal[2 * l], lny = grid.normal[2 * l + 1];
        const double e = lnx * a.wx[k] + lny * a.wy[k] - grid.rho[l];
        const double var = p.return_sigma * p.return_sigma +
                           static_cast<double>(a.per_line[l]) * p.line_sigma * p.line_sigma;
        add_point_to_line(out, lnx, lny, a.wx[k] - xe[0], a.wy[k] - xe[1], e, var, p.huber);
    }
    return out;
}

// The prior's information plus the map's normal matrix (the pose block).
FilterMatrix with_map(const FilterMatrix& info, const LineSystem& map) {
    FilterMatrix system = info;
    for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) system[r * N + s] += map.h[r * 3 + s];
    return system;
}

// The estimate xe less the prediction xp, the heading wrapped.
FilterVector offset_of(const FilterVector& xe, const FilterVector& xp) {
    FilterVector offset{};
    for (Index i = 0; i < N; ++i) offset[i] = xe[i] - xp[i];
    offset[2] = wrap(offset[2]);
    return offset;
}

// One Gauss-Newton step of the estimate xe on the map's residuals and the prior (the
// prediction xp, its information `info`); `largest`: the step's largest component. False
// if the system is not positive definite.
bool gauss_newton_step(FilterVector& xe, const FilterVector& xp, const FilterMatrix& info,
                       const LineSystem& map, double& largest) {
    FilterMatrix l = with_map(info, map);
    const FilterVector offset = offset_of(xe, xp);
    FilterVector gradient{};
    for (Index i = 0; i < N; ++i) {
        double v = i < 3 ? map.g[i] : 0.0;
        for (Index k = 0; k < N; ++k) v += info[i * N + k] * offset[k];
        gradient[i] = v;
    }
    if (!cholesky(l)) return false;
    const FilterVector step = solve(l, gradient);
    largest = 0.0;
    for (Index i = 0; i < N; ++i) {
        xe[i] -= step[i];
        largest = std::max(largest, std::fabs(step[i]));
    }
    return true;
}

// How the update's Gauss-Newton steps ended.
enum class Fit { fitted, too_few_pairs, singular };

// The update step: from the prediction xp (information `info`), Gauss-Newton steps on the
// returns' distances to their map lines, matched again at each estimate, until a step is
// below the tolerance; xe the estimate, `map` its last linearisation; the pairs and lines
// of the last association in `out`.
Fit update(const FilterVector& xp, const FilterMatrix& info, const ScanReturns& r,
           const LineGrid& grid, const FilterParams& p, FilterVector& xe, LineSystem& map,
           FilterStep& out) {
    Association a;
    a.wx.resize(r.use.size());
    a.wy.resize(r.use.size());
    a.line_of.resize(r.use.size());
    a.per_line.assign(static_cast<std::size_t>(grid.rho.size), 0);
    xe = xp;
    Fit fit = Fit::too_few_pairs;
    for (Index iteration = 0; iteration < p.iterations; ++iteration) {
        associate(xe, r, grid, p, a);
        out.pairs = a.pairs;
        out.lines = a.lines;
        if (a.pairs < p.min_pairs) return Fit::too_few_pairs;
        map = point_to_line_system(xe, a, grid, p);
        // The map's lines say nothing of this scan.
        if (map.weighted < p.min_pairs) return Fit::too_few_pairs;
        double largest = 0.0;
        if (!gauss_newton_step(xe, xp, info, map, largest)) return Fit::singular;
        fit = Fit::fitted;
        if (!(largest >= p.tolerance)) break;
    }
    return fit;
}

// The fitted estimate xe taken, unless it is too far from the prediction xp for the
// prediction's covariance (squared Mahalanobis distance above max_chi_square); its
// covariance the inverse of the prior's information plus the map's normal matrix.
void accept(FilterVector xe, const FilterVector& xp, const FilterMatrix& info,
            const LineSystem& map, const FilterParams& p, FilterStep& out) {
    const FilterVector offset = offset_of(xe, xp);
    double chi2 = 0.0;
    for (Index i = 0; i < N; ++i)
        for (Index k = 0; k < N; ++k) chi2 += offset[i] * info[i * N + k] * offset[k];
    out.chi_square = chi2;
    FilterMatrix posterior{};
    if (!(chi2 <= p.max_chi_square) || !inverse(with_map(info, map), posterior)) {
        out.status = FilterStatus::inconsistent;
        return;
    }
    xe[2] = wrap(xe[2]);
    out.state = xe;
    out.covariance = posterior;
    out.status = FilterStatus::aligned;
}

}  // namespace

Reals line_normals(View<double> alpha) {
    Reals normal(static_cast<std::size_t>(2 * alpha.size));
    for (Index l = 0; l < alpha.size; ++l) {
        normal[2 * l] = std::cos(alpha[l]);
        normal[2 * l + 1] = std::sin(alpha[l]);
    }
    return normal;
}

FilterStep filter_scan(const FilterVector& state, const FilterMatrix& covariance,
                       const double* increment, View<double> px, View<double> py,
                       const LineGrid& grid, const FilterParams& p) {
    FilterStep out{};
    FilterVector xp = state;
    FilterMatrix cp = covariance;
    if (increment) predict(xp, cp, increment, p);
    out.state = xp;
    out.covariance = cp;
    out.predicted = {xp[0], xp[1], xp[2]};
    out.status = FilterStatus::too_few_pairs;
    out.chi_square = 0.0;
    FilterMatrix info{};
    if (!inverse(cp, info)) {
        out.status = FilterStatus::inconsistent;
        return out;
    }
    const ScanReturns returns = scan_returns(px, py, cp, p);
    FilterVector xe{};
    LineSystem map{};
    const Fit fit = update(xp, info, returns, grid, p, xe, map, out);
    if (fit == Fit::fitted)
        accept(xe, xp, info, map, p, out);
    else if (fit == Fit::singular)
        out.status = FilterStatus::inconsistent;
    return out;
}

}  // namespace scanlines
