// The penalised-likelihood partition of a scan's returns into line segments and left-out
// returns: the objective and its exact optimum, shared by the methods built on it
// (scanlines/methods/partition.py and surfaces.py describe it).
#pragma once

#include <utility>

#include "scanlines/core.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines::penalised {

// How a segment's residual is measured: across its total-least-squares line, or along
// the beams (the depth along the segment's mean bearing against the lateral position).
enum class Residual { ACROSS_LINE, ALONG_BEAM };

// The objective's three settings, shared by partition and surfaces (declared once, in
// scanlines/methods/partition.py): nats of a segment, nats of a return left out, metres of
// a wall's departure from a line.
struct ObjectiveSettings {
    double penalty, clutter_cost, model_error;
};

struct Objective : ObjectiveSettings {
    Index min_points;
    Residual residual;
    // A return left out (a lone spike, a mixed pixel) does not cut the surface its
    // neighbours share: it opens no new cluster, and a run may span it.
    bool bridge_left_out;
    // The optimum searched in two stages (two_stage_runs) instead of over every start.
    bool two_stage = false;
};

// Prefix sums (rows 0..n) of w, wx, wy, wxx, wxy, wyy about (x0, y0), the held count and
// the held returns' footprint weights; row-major x COLUMNS.
struct Sums {
    static constexpr int COLUMNS = 8;
    Reals v;
    double x0, y0;
    double at(Index row, int column) const { return v[COLUMNS * row + column]; }
};

struct Runs {
    Ints a, b;
};

struct Scatter {
    double w, mx, my, sxx, sxy, syy;
};

// Each return's weight is footprint[p] / (sigma[p]^2 + model_error^2) while held, else 0.
Sums weighted_sums(const Returns& ret, const Reals& sigma, const Reals& footprint,
                   double model_error, const Flags& held);
// The same over returns lo .. hi - 1 alone (row 0: none of them), about the scan's first return.
Sums weighted_sums(const Returns& ret, const Reals& sigma, const Reals& footprint,
                   double model_error, const Flags& held, Index lo, Index hi);


// The weighted scatter of the returns of runs [a, b] (about their weighted mean).
Scatter scatter(const Sums& sums, Index a, Index b);

// The smaller and larger eigenvalue of the scatter [[sxx, sxy], [sxy, syy]].
std::pair<double, double> eigenvalues(double sxx, double sxy, double syy);

// A segment's chi2 along the beams from its weighted scatter s (about its mean, which is
// relative to (x0, y0)) and the sum of its returns' footprint weights.
double along_beam_chi2(const Scatter& s, double footprints, double x0, double y0,
                       double model_error);

struct FittedLine {
    double rho, alpha, direction_variance, w;
};

// The weighted total-least-squares line of run [a, b].
FittedLine line_of(const Sums& sums, Index a, Index b);

// Whether returns p and q (beams apart) may lie on one surface: no farther apart than a
// surface seen at up to 80 deg of incidence puts them, plus sigmas of their difference.
bool continuous(const Returns& ret, Index p, Index q, Index beams, double step,
                const Reals& sigma, double sigmas);

// The optimal runs [a, b]: the dynamic programme with PELT pruning.
// `at`: the return position of each row of `sums` (empty: row p is return p); `allowed`:
// the starts a segment longer than a few returns may have (empty: every start).
Runs optimal_runs(const Sums& sums, const Flags& opens, const Objective& objective,
                  const Ints& at, const Flags& allowed);

// The programme's state: each end's least cost and best start, and the step + min_points at
// which each start was pruned (n + 1: never).
struct Search {
    Reals best;
    Ints start, expires;
};

// Steps from .. n of the programme into `search`, which holds steps 1 .. from - 1 of a search
// over sums whose rows 0 .. from - 1 were the same (bit for bit), so that the result is the
// whole search's over these sums; from = 1 (or a search of another size): all of it.
void search_from(const Sums& sums, const Flags& opens, const Objective& objective,
                 const Ints& at, const Flags& allowed, Search& search, Index from);

// The runs the best starts of a search trace back from its last end.
Runs traced_runs(const Search& search);

struct ScanPartition {
    Runs runs;
    Flags held;
    Sums sums;
    Ints gap;
};

// The best partition of a scan's returns: runs chosen, outliers left out, up to three
// rounds; footprint: each return's weight in the objective (1: one return, one observation).
ScanPartition best_partition(const Returns& ret, const Reals& sigma, const Reals& footprint,
                         Index n_beams, double step, const Objective& objective);

// A full circle's returns rotated to start after their widest gap, and whether they close
// into a ring.
std::pair<Returns, bool> seam_at_widest_gap(Returns ret, const Ints& gap, Index n_beams);

// The position of the corner where neighbouring runs i and j meet, or -1: their lines turn
// by more than sigmas standard deviations of the turn and cross within the facing returns'
// spacing plus sigmas noise sigmas of them.
Index corner_between(const Returns& ret, const Sums& sums, const Reals& sigma, const Runs& runs,
                     Index i, Index j, double sigmas);

// Whether a scan is a full circle, whether its returns close into a ring, its beam count.
struct ScanShape {
    bool full_circle, ring;
    Index n_beams;
};

// Breakpoints where a surface ends and corners where two segments meet, read between
// consecutive returns of `positions` (every return, or the held ones only): a breakpoint
// at the first of two returns farther apart than a surface can put them, a corner between
// neighbouring runs whose lines turn and meet (corner_between).
std::pair<Ints, Ints> events(const Returns& ret, const ScanPartition& part, const Reals& sigma,
                             const Ints& positions, double step, ScanShape shape);

// The runs (their numbers) that hold at least min_points returns in their fit and are at least min_length long.
Ints kept_runs(const Returns& ret, const Flags& held, const Runs& runs, Index min_points,
                double min_length);

// A scan's valid returns as the partition takes them: a full circle rotated to start after
// its widest gap (ring: whether it closes), and each return's range noise (noise_sigma, or
// NaN for the sensor's noise line, else the scan's own).
struct ScanReturns {
    Returns ret;
    Reals sigma;
    bool ring;
};
ScanReturns scan_returns(View<double> ranges, View<bool> valid, const Stack& sensor,
                         double noise_sigma);

// The best partition of scan's returns; a closed ring is cut where the first optimum had a
// boundary and solved again (scan and footprint rotated with it).
ScanPartition ring_partition(ScanReturns& scan, Reals& footprint, Index n_beams, double step,
                         const Objective& objective);

// The returns held in a fit, the runs `kept` renumbered to them, and their range noise
// (range_sigma, or NaN for each return's own).
struct HeldRuns {
    Returns ret;
    Ints a, b;
    Reals sigma;
};
HeldRuns held_runs(const ScanReturns& scan, const ScanPartition& part, const Ints& kept,
                   double range_sigma);

// The beams of the returns the partition left out.
Ints left_out(const Returns& ret, const ScanPartition& part);

}  // namespace scanlines::penalised
