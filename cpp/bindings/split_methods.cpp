#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/split_methods.hpp"

namespace scanlines::bind {

namespace {

// The settings record of scanlines/methods/iepf.py and split_merge.py, group by group
// (the fields only split_merge has are NaN for iepf and pdbs).
SplitSettings split_settings(const nb::dict& record) {
    auto optional = [](const nb::dict& group, const char* name) {
        return group.contains(name) ? setting<double>(group, name) : NAN;
    };
    nb::dict clustering = group(record, "clustering"), segments = group(record, "segments");
    return {{rule_spec_of(clustering), optional(clustering, "outlier_distance")},
            {setting<double>(segments, "split_distance"),
             setting_in(segments, "split_reference", CHORD, LINE), optional(segments, "merge_chi2")},
            output_of(group(record, "output"), group(record, "events"))};
}

}  // namespace

void bind_split_methods(nb::module_& m) {
    m.def("iepf_stack", &stack_kernel<split_settings, iepf_stack>,
          "Iterative end-point fit on each row of a stack of scans: one flat table.");
    m.def("split_merge_stack", &stack_kernel<split_settings, split_merge_stack>,
          "Split-and-merge on each row of a stack of scans: one flat table.");
}

}  // namespace scanlines::bind
