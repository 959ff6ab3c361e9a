// Line segments of the surfaces a scan sees: the penalised partition with the residual along
// the beams and each return weighed by its footprint, events where surfaces end, and the
// pieces of one surface pooled into one line (scanlines/methods/surfaces.py describes it).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/methods/penalised.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines {

// The settings of scanlines/methods/surfaces.py, grouped as it declares them.
struct SurfacesSettings {
    double noise_sigma;  // noise; NaN: the noise line
    struct Segments : penalised::ObjectiveSettings {
        double footprint;
        bool two_stage;  // the two-stage search (penalised::two_stage_runs)
    } segments;
    OutputBounds output;
};

ScanResult surfaces_scan(View<double> ranges, View<bool> valid, const Stack& sensor,
                         const SurfacesSettings& s);

Table surfaces_stack(const Stack& stack, const SurfacesSettings& s);

}  // namespace scanlines
