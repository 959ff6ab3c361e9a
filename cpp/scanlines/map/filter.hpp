// The localisation filter's kernel (src/scanlines/map/filter.py documents the model): an
// extended Kalman filter on a line map, one scan at a time, whose state is the pose and the
// odometry's systematic errors.
#pragma once

#include <array>

#include "scanlines/core.hpp"

namespace scanlines {

// The filter's state: the sensor's x, y, theta (metres, radians), the odometry's heading drift
// per metre driven (radians per metre), its distance scale error (a share: 0.02 = 2 % too
// long), and where the sensor sits in the odometry's frame (x, y metres: the lever that
// moves the sensor when the robot turns in place).
constexpr Index FILTER_STATE = 7;
using FilterVector = std::array<double, FILTER_STATE>;
using FilterMatrix = std::array<double, FILTER_STATE * FILTER_STATE>;  // row-major

// A uniform grid over map lines: cell (i, j) (i along x) lists the lines within the grid's
// reach of the cell, ids cell_lines[cell_start[c] .. cell_start[c + 1]) of cell c = i * ny + j.
struct CellGrid {
    double x0, y0, cell;
    Index nx, ny;
    View<Index> cell_start, cell_lines;
};

// The map's lines and two grids over them: `wide`, whose reach is the largest gate, and
// `near`, finer, whose reach is `near_reach`: a return whose gate is no larger is looked up
// there, among fewer lines (the same nearest line: every line within its gate is listed in
// both, in the order of their ids). `sides`: the sides each line was seen from (bit 1: the side
// its normal points to, bit 2: the other); a return matches a line only from a side it was
// seen from. `normal`: each line's unit normal (cos alpha, sin alpha), as line_normals gives it.
struct LineGrid {
    View<double> rho, normal, start, end;  // normal, start, end: L x 2, row-major
    View<Index> sides;
    CellGrid wide, near;
    double near_reach;
};

struct FilterParams {
    // The odometry increment's noise: a floor and a share of the distance (x, y); a floor, a
    // share of the turn and a share per metre driven (theta); the drift's and the scale's
    // random walk per metre driven.
    double odometry_floor, odometry_per_metre;
    double turn_floor, turn_per_radian, turn_per_metre;
    double drift_walk, scale_walk;
    // Association: a return's local line (from `normal_window` neighbours each side within
    // `neighbour_gap`, its spread across no more than `flatness` times its spread along) must
    // lie within `normal_tolerance` (cosine) of the map line's; the gate of a return is
    // gate_base + gate_sigmas * (its position's standard deviation), within [gate_min,
    // gate_max]; a map line counts when at least `line_returns` returns meet it.
    Index normal_window;
    double neighbour_gap, flatness, normal_cosine;
    double gate_base, gate_sigmas, gate_min, gate_max;
    Index line_returns;
    // The residual's noise: a return's own, and a map line's (shared by the returns on it:
    // a line's weight is capped); the Huber width in standard deviations.
    double return_sigma, line_sigma, huber;
    // Gauss-Newton: the most steps and the step at which they stop; the returns a fit needs;
    // the largest squared Mahalanobis distance of the correction from the prediction.
    Index iterations;
    double tolerance;
    Index min_pairs;
    double max_chi_square;
    Index max_points;
};

// What became of a scan: aligned, too few returns near a map line, or a correction too far
// from the prediction for its covariance.
enum class FilterStatus : int { aligned = 0, too_few_pairs = 1, inconsistent = 2 };

struct FilterStep {
    FilterVector state;
    FilterMatrix covariance;
    std::array<double, 3> predicted;
    Index pairs;
    Index lines;
    double chi_square;
    FilterStatus status;
};

// The unit normals (cos, sin) of lines at angles `alpha`, L x 2 row-major: worked out once
// per map, not for each return's candidate lines.
Reals line_normals(View<double> alpha);

// The filter's step for one scan: predict with the odometry `increment` (x, y, theta in the
// last pose's frame; null: the first scan, no prediction), then associate the scan's returns
// (x, y in the sensor frame, beam order) with the map's lines and update.
FilterStep filter_scan(const FilterVector& state, const FilterMatrix& covariance,
                       const double* increment, View<double> x, View<double> y,
                       const LineGrid& grid, const FilterParams& params);

}  // namespace scanlines
