// scanlines._core: the compiled kernels. Each method's binding lives in its own file.
#include "arrays.hpp"
#include "scanlines/steps/events.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines::bind {
void bind_adaptive(nb::module_& m);
void bind_paper(nb::module_& m);
void bind_partition(nb::module_& m);
void bind_split_methods(nb::module_& m);
void bind_fits(nb::module_& m);
void bind_numbers(nb::module_& m);
void bind_segmentation(nb::module_& m);
void bind_filter(nb::module_& m);
}

NB_MODULE(_core, m) {
    m.doc() = "The compiled kernels of scanlines (C++17); called by the methods' modules.";
#if defined(__clang__)
    m.attr("COMPILER") = "clang " __clang_version__;
#elif defined(__GNUC__)
    m.attr("COMPILER") = "gcc " __VERSION__;
#elif defined(_MSC_VER)
    m.attr("COMPILER") = "msvc " NB_STRINGIFY(_MSC_VER);
#else
    m.attr("COMPILER") = "unknown";
#endif
    m.attr("MIN_NOISE_SIGMA") = scanlines::MIN_NOISE_SIGMA;
    m.attr("MAX_BRIDGED_GAP") = scanlines::MAX_BRIDGED_GAP;
    m.attr("CORNER_SIGMAS") = scanlines::CORNER_SIGMAS;
    scanlines::bind::bind_adaptive(m);
    scanlines::bind::bind_paper(m);
    scanlines::bind::bind_partition(m);
    scanlines::bind::bind_split_methods(m);
    scanlines::bind::bind_fits(m);
    scanlines::bind::bind_numbers(m);
    scanlines::bind::bind_segmentation(m);
    scanlines::bind::bind_filter(m);
}
