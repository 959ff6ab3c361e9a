#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/paper.hpp"

namespace scanlines::bind {

namespace {

// The settings record of scanlines/methods/paper.py, group by group.
PaperSettings paper_settings(const nb::dict& record) {
    nb::dict clustering = group(record, "clustering");
    return {{setting_in(clustering, "window", 1, MAX_SETTING_COUNT), setting<double>(clustering, "k")},
            output_bounds_of(group(record, "output"))};
}

}  // namespace

void bind_paper(nb::module_& m) {
    m.def("paper_stack", &grid_stack_kernel<paper_settings, paper_stack>,
          "The paper method on each row of a stack of scans: one flat table.");
}

}  // namespace scanlines::bind
