// Line segments as the exact penalised-likelihood partition of a scan's returns
// (scanlines/methods/partition.py has the method's description).
#pragma once

#include <utility>

#include "scanlines/core.hpp"
#include "scanlines/methods/penalised.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

// The settings of scanlines/methods/partition.py, grouped as it declares them.
struct PartitionSettings {
    double noise_sigma;  // noise; NaN: the noise line
    penalised::ObjectiveSettings segments;
    struct Kept : OutputBounds {
        double max_rho_sigma;  // inf: keep every segment
    } output;
};

ScanResult partition_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                          const PartitionSettings& s);

Table partition_stack(const Stack& stack, const PartitionSettings& s);

// The optimal runs [a, b] of every return of x, y (no outliers chosen, no joining): the
// dynamic programme alone, for the tests that check it against enumeration.
std::pair<Ints, Ints> partition_optimal_runs(const Reals& x, const Reals& y, const Reals& sigma,
                                             double model_error, const Flags& opens,
                                             double penalty, double clutter_cost,
                                             Index min_points);

}  // namespace scanlines
