// The methods that split clusters at their farthest point: iepf (and pdbs, iepf with
// another clustering rule) and split_merge (scanlines/methods/iepf.py, split_merge.py).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

struct SplitSettings {
    double split_distance;
    Index split_reference;  // CHORD or LINE
    // split_merge only:
    Index min_points;
    double min_length, range_sigma, outlier_distance, merge_chi2;
};

Table iepf_stack(const Stack& stack, const SplitSettings& s, const RuleSpec& rule,
                 const Output& out);

Table split_merge_stack(const Stack& stack, const SplitSettings& s, const RuleSpec& rule,
                        const Output& out);

}  // namespace scanlines
