// The methods that split clusters at their farthest point: iepf (and pdbs, iepf with
// another clustering rule) and split_merge (scanlines/methods/iepf.py, split_merge.py).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

// The settings of scanlines/methods/iepf.py and split_merge.py, grouped as they declare them.
struct SplitSettings {
    struct Clustering {
        RuleSpec rule;
        double outlier_distance;  // split_merge only: lone returns dropped first
    } clustering;
    struct Segments {
        double split_distance;
        Index split_reference;  // CHORD or LINE
        double merge_chi2;      // split_merge only
    } segments;
    Output output;  // the output and events settings
};

Table iepf_stack(const Stack& stack, const SplitSettings& s);

Table split_merge_stack(const Stack& stack, const SplitSettings& s);

}  // namespace scanlines
