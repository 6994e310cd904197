// Photometric refinement of a mesh that keeps it a closed 2-manifold without self-intersections
// (docs/refine.md): coarse-to-fine gradient descent on the pairwise ZNCC energy
// (refine/photometric_gradient.h) plus a thin-plate term, every step applied by
// MoveVerticesSafely (refine/mesh_moves.h). The faces are never changed.
//
//   RefineStats stats = RefineMesh(&mesh, cameras, RefinePairs(scene, neighbours), options,
//                                  [](const RefineIteration& it) { log(it); });
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "mesh/mesh.h"
#include "refine/refine_options.h"
#include "scene/scene.h"
#include "scene/view_selection.h"
#include "sweep/sweep_kernel.h"

namespace ms {

struct RefineIteration {
  int level = 0;      // pyramid level (0: full size)
  int iteration = 0;  // 1-based, over all levels
  double energy = 0;  // mean (1 - ZNCC) over the defined pixels, before the step
  // The previous step raised the energy: it was undone, and this one is half as long.
  bool rejected = false;
  double step_scale = 1;  // of the step options (backtracking), in (0, 1]
  int64_t pixels = 0;     // defined pixels over all pairs
  int64_t moved = 0, halved = 0, refused = 0;
  double largest_move = 0;   // mesh units
  int checks = 0;            // checker passes over the whole mesh for this step
  double check_seconds = 0;  // their time
  double seconds = 0;
};

struct RefineStats {
  std::vector<RefineIteration> iterations;
  double final_energy = 0;     // mean (1 - ZNCC) of the returned mesh at the finest level
  int64_t splits = 0;          // edges split by remeshing (vertices added)
  int64_t splits_refused = 0;  // splits the checker objected to (undone)
  double seconds = 0;
};

// Where a refinement stands between two iterations: what a checkpoint holds besides the mesh
// (whose faces remeshing may have changed), so that resuming gives the mesh an uninterrupted
// run gives, bit for bit.
struct RefineState {
  int level_index = 0;         // levels begun, from the coarsest, minus 1
  int iteration_in_level = 0;  // iterations done at that level
  int iterations_done = 0;     // over all levels
  double scale = 1;            // backtracking's step scale
  double accepted_energy = 0;
  std::vector<Eigen::Vector3d> accepted;  // the last accepted vertices; empty before the first
  double tolerance = 0;                   // of the checks, fixed at the start
};

// Every camera with each of its neighbours (scene/view_selection.h), in camera order.
std::vector<std::pair<int, int>> RefinePairs(const Scene& scene, const NeighbourOptions& options);

// `cameras[i]` is camera i at full size (gray float, no distortion: LoadSweepCamera); `pairs`
// index `cameras` as (reference, neighbour). `mesh` should be a closed 2-manifold robust in
// floating point (what `reconstruct` writes); its faces stay as they are.
// With `resume` (a checkpoint's state, `mesh` being the checkpoint's mesh) it goes on from
// there; `checkpoint` is called after every iteration with the mesh and the state to resume from.
RefineStats RefineMesh(Mesh* mesh, const std::vector<SweepCamera>& cameras,
                       const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                       const std::function<void(const RefineIteration&)>& progress = {},
                       const RefineState* resume = nullptr,
                       const std::function<void(const Mesh&, const RefineState&)>& checkpoint = {});

}  // namespace ms
