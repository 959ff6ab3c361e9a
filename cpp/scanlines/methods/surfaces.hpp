// Line segments of the surfaces a scan sees: the penalised partition with the residual along
// the beams and each return weighed by its footprint, events where surfaces end, and the
// pieces of one surface pooled into one line (scanlines/methods/surfaces.py describes it).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

struct SurfacesSettings {
    double penalty, clutter_cost, model_error, footprint;
    Index min_points;
    double min_length;
    double noise_sigma;  // NaN: the noise line
    double range_sigma;  // NaN: the noise line
};

ScanResult surfaces_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                         const SurfacesSettings& s);

Table surfaces_stack(const Stack& stack, const SurfacesSettings& s);

}  // namespace scanlines
