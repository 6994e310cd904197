// The refinement of a mesh file as `manisweep refine` and `reconstruct --refine` run it:
// read the scene, its images and the mesh (a closed 2-manifold), refine (refine/refiner.h),
// write the result and report check-mesh's verdict on it. A checkpoint is written beside the
// output after every iteration (refine/refine_checkpoint.h) and removed at the end; with
// `resume` the refinement goes on from it. Ctrl-C stops after the next checkpoint (exit 130).
// Throws InputError for bad input.
#pragma once

#include <string>

#include "refine/refine_options.h"
#include "scene/view_selection.h"

namespace ms::app {

void RefineMeshFile(const std::string& input, const std::string& mesh_path,
                    const std::string& output, const RefineOptions& refine,
                    const NeighbourOptions& neighbours, bool ascii = false, bool resume = false);

}  // namespace ms::app
