// The refinement of a mesh file as `manisweep refine` and `reconstruct --refine` run it:
// read the scene, its images and the mesh (a closed 2-manifold), refine (refine/refiner.h),
// write the result and report check-mesh's verdict on it. A checkpoint is written beside the
// output after every iteration (refine/refine_checkpoint.h) and removed at the end; with
// `resume` the refinement goes on from it. Ctrl-C stops after the next checkpoint (exit 130).
// Throws InputError for bad input.
//
// With `workers`, the pairs' gradients are computed by the workers connected to that transport
// (coordinator/refine_dispatcher.h): `reconstruct --refine` and `coordinator --refine` pass their
// own. The refined mesh is the same bits either way.
#pragma once

#include <functional>
#include <string>

#include "coordinator/job_scheduler.h"
#include "proto/transport.h"
#include "proto/wire_limits.h"
#include "refine/refine_options.h"
#include "scene/view_selection.h"

namespace ms::app {

struct RefineWorkers {
  ServerTransport* transport = nullptr;  // bound; the workers connect to it
  SchedulerOptions scheduler;
  WireLimits limits;
  // Polled by the network loop: true stops (Ctrl-C: exit 130; otherwise "no worker left").
  std::function<bool()> stop_requested;
};

void RefineMeshFile(const std::string& input, const std::string& mesh_path,
                    const std::string& output, const RefineOptions& refine,
                    const NeighbourOptions& neighbours, bool ascii = false, bool resume = false,
                    const RefineWorkers* workers = nullptr);

}  // namespace ms::app
