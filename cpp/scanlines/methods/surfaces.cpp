#include "scanlines/methods/surfaces.hpp"

#include <algorithm>
#include <cmath>

#include "scanlines/methods/penalised.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

namespace {

using namespace penalised;

constexpr std::size_t LOOK_BEHIND = 3;
// The least a return weighs: at the finest sampling ten returns count as one observation,
// which keeps a corner's evidence within the partition's look-back of 256 returns.
constexpr double LIGHTEST_RETURN = 0.1;

// Each return's weight in the objective: one observation per `footprint` metres of wall at
// most, so that a finely sampled wall's correlated errors are not counted as independent.
Reals footprint_weights(const Returns& ret, double step, double footprint) {
    Reals out(ret.r.size(), 1.0);
    if (footprint > 0.0)
        for (std::size_t p = 0; p < out.size(); ++p)
            out[p] = std::clamp(ret.r[p] * step / footprint, LIGHTEST_RETURN, 1.0);
    return out;
}

// The raw weighted sums (w, wx, wy, wxx, wxy, wyy, footprints) of run [a, b].
struct Raw {
    double v[7];
};

Raw raw_sums(const Sums& sums, Index a, Index b) {
    Raw out;
    for (int c = 0; c < 6; ++c) out.v[c] = sums.at(b + 1, c) - sums.at(a, c);
    out.v[6] = sums.at(b + 1, 7) - sums.at(a, 7);
    return out;
}

double raw_chi2(const Sums& sums, const Raw& raw, double model_error) {
    double w = raw.v[0];
    double mx = raw.v[1] / w, my = raw.v[2] / w;
    Scatter s{w, mx, my, raw.v[3] - w * mx * mx, raw.v[4] - w * mx * my, raw.v[5] - w * my * my};
    return along_beam_chi2(s, raw.v[6], sums.x0, sums.y0, model_error);
}

// Groups of kept runs that are pieces of one surface: a run joins the group of one of the
// LOOK_BEHIND runs before it (the nearest that agrees) when one line explains the group and
// the run for less than the price of the segment it saves (the objective's penalty).
Ints surface_groups(const Sums& sums, const Runs& runs, const Ints& kept, double penalty,
                    double model_error) {
    Ints group(kept.size(), 0);
    std::vector<Raw> pooled;
    Reals pooled_chi2;
    for (std::size_t k = 0; k < kept.size(); ++k) {
        Raw piece = raw_sums(sums, runs.a[kept[k]], runs.b[kept[k]]);
        double piece_chi2 = raw_chi2(sums, piece, model_error);
        Index joined = -1;
        for (std::size_t back = 1; back <= LOOK_BEHIND && back <= k && joined < 0; ++back) {
            Index g = group[k - back];
            Raw joint = pooled[g];
            for (int c = 0; c < 7; ++c) joint.v[c] += piece.v[c];
            double joint_chi2 = raw_chi2(sums, joint, model_error);
            if (0.5 * (joint_chi2 - pooled_chi2[g] - piece_chi2) <= penalty) {
                joined = g;
                pooled[g] = joint;
                pooled_chi2[g] = joint_chi2;
            }
        }
        if (joined < 0) {
            joined = static_cast<Index>(pooled.size());
            pooled.push_back(piece);
            pooled_chi2.push_back(piece_chi2);
        }
        group[k] = joined;
    }
    return group;
}

// Give each segment of a group of more than one the line of the group's returns together.
void pool_lines(ScanResult& result, const Returns& ret, const Reals& sigma, const Ints& a,
                const Ints& b, const Ints& group, double angle_min) {
    const double cos_t = std::cos(angle_min), sin_t = std::sin(angle_min);
    const Index groups = group.empty() ? 0 : *std::max_element(group.begin(), group.end()) + 1;
    for (Index g = 0; g < groups; ++g) {
        Ints members;
        for (std::size_t k = 0; k < group.size(); ++k)
            if (group[k] == g) members.push_back(static_cast<Index>(k));
        if (members.size() < 2) continue;
        Returns joint;
        Reals joint_sigma;
        for (Index k : members)
            for (Index p = a[k]; p <= b[k]; ++p) {
                joint.index.push_back(ret.index[p]);
                joint.r.push_back(ret.r[p]);
                joint.x.push_back(ret.x[p]);
                joint.y.push_back(ret.y[p]);
                joint_sigma.push_back(sigma[p]);
            }
        const Index count = joint.size();
        Moments moments = prefix_moments(joint.x, joint.y);
        Line line = tls_run(moments, 0, count - 1);
        Reals covariance = run_covariances(joint.r, joint.x, joint.y, {line.rho}, {line.alpha},
                                           {0}, {count - 1}, joint_sigma, true);
        const double c = std::cos(line.alpha), s = std::sin(line.alpha);
        for (Index k : members) {
            Index at = 0;
            while (result.first[at] != ret.index[a[k]]) ++at;
            double* row = &result.lines[LINE_COLUMNS * at];
            double squares = 0.0;
            for (Index p = a[k]; p <= b[k]; ++p) {
                double off = ret.x[p] * c + ret.y[p] * s - line.rho;
                squares += off * off;
            }
            row[0] = line.rho;
            row[1] = wrap_angle(line.alpha + angle_min);
            const Index ends[2] = {a[k], b[k]};
            for (int e = 0; e < 2; ++e) {
                Index p = ends[e];
                double off = ret.x[p] * c + ret.y[p] * s - line.rho;
                double px = ret.x[p] - off * c, py = ret.y[p] - off * s;
                row[2 + 2 * e] = cos_t * px - sin_t * py;
                row[3 + 2 * e] = sin_t * px + cos_t * py;
            }
            row[6] = std::sqrt(squares / static_cast<double>(b[k] - a[k] + 1));
            std::copy(covariance.begin(), covariance.end(), result.covariances.begin() + 4 * at);
        }
    }
}

}  // namespace

ScanResult surfaces_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                         const SurfacesSettings& s) {
    const Index n_beams = ranges.size;
    ScanReturns scan = scan_returns(ranges, valid, sensor, s.noise_sigma);
    if (scan.ret.size() == 0) return empty_result({}, {});
    const Objective objective{s.segments, s.output.min_points, Residual::ALONG_BEAM, true,
                              s.segments.two_stage};
    Reals weights = footprint_weights(scan.ret, sensor.step, s.segments.footprint);
    ScanPartition part = ring_partition(scan, weights, n_beams, sensor.step, objective);
    Ints in_fit;  // events between held returns: a return left out inside a surface is none
    for (std::size_t p = 0; p < part.held.size(); ++p)
        if (part.held[p]) in_fit.push_back(static_cast<Index>(p));
    auto [breakpoints, corners] = events(scan.ret, part, scan.sigma, in_fit, sensor.step,
                                         {sensor.full_circle, scan.ring, n_beams});
    Ints kept_ids = kept_runs(scan.ret, part.held, part.runs, s.output.min_points, s.output.min_length);
    Ints group = surface_groups(part.sums, part.runs, kept_ids, s.segments.penalty,
                                 s.segments.model_error);
    HeldRuns held = held_runs(scan, part, kept_ids, s.output.range_sigma);
    Moments moments = prefix_moments(held.ret.x, held.ret.y);
    ScanResult result =
        assemble(held.ret, TLS, moments, held.a, held.b, sensor.angle_min, held.sigma,
                 {breakpoints, corners, left_out(scan.ret, part)}, n_beams, scan.ring);
    pool_lines(result, held.ret, held.sigma, held.a, held.b, group, sensor.angle_min);
    return result;
}

Table surfaces_stack(const Stack& stack, const SurfacesSettings& s) {
    return each_row(stack, surfaces_scan, s);
}

}  // namespace scanlines
