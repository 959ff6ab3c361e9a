#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/split_methods.hpp"

namespace scanlines::bind {

namespace {

template <Table (*kernel)(const Stack&, const SplitSettings&, const RuleSpec&, const Output&)>
nb::tuple split_stack(const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
                      const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin,
                      double step, bool full_circle, double angle_min,
                      std::pair<double, double> noise, const nb::dict& settings,
                      const nb::dict& rule, const nb::dict& out) {
    Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
    auto optional = [&](const char* name) {
        return settings.contains(name) ? nb::cast<double>(settings[name]) : NAN;
    };
    SplitSettings s{setting<double>(settings, "split_distance"),
                    setting<Index>(settings, "split_reference"),
                    setting<Index>(settings, "min_points"),
                    setting<double>(settings, "min_length"),
                    setting<double>(settings, "range_sigma"),
                    optional("outlier_distance"),
                    optional("merge_chi2")};
    RuleSpec spec = rule_spec_of(rule);
    Output output = output_of(out);
    Table table;
    {
        nb::gil_scoped_release unlocked;
        table = kernel(stack, s, spec, output);
    }
    return table_to_numpy(std::move(table));
}

}  // namespace

void bind_split_methods(nb::module_& m) {
    m.def("iepf_stack", &split_stack<iepf_stack>,
          "Iterative end-point fit on each row of a stack of scans: one flat table.");
    m.def("split_merge_stack", &split_stack<split_merge_stack>,
          "Split-and-merge on each row of a stack of scans: one flat table.");
}

}  // namespace scanlines::bind
