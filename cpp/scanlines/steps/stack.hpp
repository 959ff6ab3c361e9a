// A stack of scans through a method: each scan's result appended to one flat table
// (scanlines/steps/stack.py; ExtractionTable.of_flat_table reads it).
#pragma once

#include <array>

#include "scanlines/core.hpp"

namespace scanlines {

struct Table {
    ScanResult columns;                  // every scan's arrays, scan after scan
    std::vector<std::array<Index, 4>> counts;  // per scan: segments, breakpoints, corners, outliers

    void add(const ScanResult& result) {
        auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
        append(columns.first, result.first);
        append(columns.last, result.last);
        append(columns.n_points, result.n_points);
        append(columns.lines, result.lines);
        append(columns.covariances, result.covariances);
        append(columns.breakpoints, result.breakpoints);
        append(columns.corners, result.corners);
        append(columns.outliers, result.outliers);
        append(columns.end_kinds, result.end_kinds);
        counts.push_back({result.segments(), static_cast<Index>(result.breakpoints.size()),
                          static_cast<Index>(result.corners.size()),
                          static_cast<Index>(result.outliers.size())});
    }
};

// The bearing tables and shape of a stack of scans of one sensor.
struct Stack {
    const double* ranges;  // rows x beams, row-major
    const bool* valid;     // rows x beams
    Index rows, beams;
    View<double> cos, sin;
    double step;  // angular increment, its sign dropped
    bool full_circle;
    double angle_min;
    NoiseLine noise;  // a sensor profile's, or NaN: each scan's own
    View<double> row_ranges(Index row) const { return {ranges + row * beams, beams}; }
    View<bool> row_valid(Index row) const { return {valid + row * beams, beams}; }
};

// Each row of the stack through a method's scan kernel, scan(ranges, valid, stack,
// settings...): one flat table.
template <class ScanKernel, class... Settings>
Table each_row(const Stack& stack, ScanKernel scan, const Settings&... settings) {
    Table table;
    for (Index row = 0; row < stack.rows; ++row)
        table.add(scan(stack.row_ranges(row), stack.row_valid(row), stack, settings...));
    return table;
}

}  // namespace scanlines
