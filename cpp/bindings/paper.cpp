#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/paper.hpp"

namespace scanlines::bind {

namespace {

// The settings record of scanlines/methods/paper.py, group by group.
PaperSettings paper_settings(const nb::dict& record) {
    nb::dict clustering = group(record, "clustering");
    return {{setting<Index>(clustering, "window"), setting<double>(clustering, "k")},
            output_bounds_of(group(record, "output"))};
}

}  // namespace

void bind_paper(nb::module_& m) {
    m.def(
        "paper_stack",
        [](const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
           const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin, double step,
           bool full_circle, double angle_min, std::pair<double, double> noise,
           const nb::dict& settings, const InReals& grid) {
            Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
            PaperSettings s = paper_settings(settings);
            Reals thresholds = vector_of(grid);
            Table table;
            {
                nb::gil_scoped_release unlocked;
                table = paper_stack(stack, s, thresholds);
            }
            return table_to_numpy(std::move(table));
        },
        "The paper method on each row of a stack of scans: one flat table.");
}

}  // namespace scanlines::bind
