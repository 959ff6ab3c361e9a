// The Electronics 2022 paper's line-segment extractor as printed, one choice per step
// (scanlines/methods/paper.py has the method's steps and their equations).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

// The settings of scanlines/methods/paper.py, grouped as it declares them.
struct PaperSettings {
    struct Clustering {
        Index window;  // Step 3: the mean filter's window N
        double k;      // Step 4: D = k rho dtheta
    } clustering;
    OutputBounds output;  // range_sigma NaN: the noise line
};

// The method on one scan; grid: the thresholds dkth of Steps 6-7 (at least one).
ScanResult paper_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                      const PaperSettings& s, const Reals& grid);

Table paper_stack(const Stack& stack, const PaperSettings& s, const Reals& grid);

}  // namespace scanlines
