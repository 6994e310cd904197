// Photometric refinement of a mesh that keeps it a closed 2-manifold without self-intersections
// (docs/design/refine.md): coarse-to-fine gradient descent on the pairwise ZNCC energy
// (refine/photometric_gradient.h) plus a thin-plate term, every step applied by
// MoveVerticesSafely (refine/mesh_moves.h). The faces are never changed.
//
//   RefineHooks hooks;
//   hooks.progress = [](const RefineIteration& it) { log(it); };
//   RefineStats stats = RefineMesh(&mesh, cameras, RefinePairs(scene, neighbours), options, hooks);
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "mesh/mesh.h"
#include "refine/photometric_gradient.h"
#include "refine/refine_options.h"
#include "scene/scene.h"
#include "scene/view_selection.h"
#include "sweep/sweep_kernel.h"

namespace ms {

struct RefineIteration {
  int level = 0;         // pyramid level (0: full size)
  int iteration = 0;     // 1-based, over all levels
  int64_t vertices = 0;  // of the mesh the step starts from
  double energy = 0;     // mean (1 - ZNCC) over the defined pixels, before the step
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
  int64_t collapses = 0;       // edges collapsed by remeshing (vertices removed)
  int64_t collapses_refused = 0;
  // Levels whose remeshing was undone: it moved the surface across or too near a camera.
  int64_t remeshings_undone = 0;
  int64_t flips = 0;          // edges flipped by remeshing
  int64_t flips_refused = 0;  // flips the checker objected to (undone)
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
  double camera_clearance = 0;            // the same (0 from checkpoints older than it: none)
  std::vector<int32_t> stuck;             // vertices whose last move was refused (--refine.unfold)
};

// Every camera with each of its neighbours (scene/view_selection.h), in camera order.
std::vector<std::pair<int, int>> RefinePairs(const Scene& scene, const NeighbourOptions& options);

// Camera `camera` as refinement sees it at pyramid level `level` (the sweep's scaling), its
// image in double. Workers and the local loop both make their views with this.
RefineView RefineViewAtLevel(const SweepCamera& camera, int level);

// The gradient of every pair of `pairs` for `mesh` at pyramid level `level`, in pair order
// (the refiner sums them in that order). Returns false if interrupted: RefineMesh then throws
// RefineInterrupted. The default computes them here on `threads`; the coordinator's
// RefineDispatcher computes them on workers (docs/design/refine.md "Distributed").
using PairGradientSource =
    std::function<bool(const Mesh& mesh, int level, std::vector<PairGradient>* per_pair)>;

// Thrown by RefineMesh when the pair gradient source was interrupted (Ctrl-C); the last
// checkpoint stays valid.
struct RefineInterrupted : std::runtime_error {
  RefineInterrupted() : std::runtime_error("refinement interrupted") {}
};

// What a caller may add to RefineMesh, all optional.
struct RefineHooks {
  std::function<void(const RefineIteration&)> progress;  // after every iteration
  // A checkpoint's state to go on from (the mesh passed being the checkpoint's mesh).
  const RefineState* resume = nullptr;
  // After every iteration: the mesh and the state to resume from.
  std::function<void(const Mesh&, const RefineState&)> checkpoint;
  PairGradientSource pair_gradients;  // empty: computed in this process
};

// `cameras[i]` is camera i at full size (gray float, no distortion: LoadSweepCamera; with
// hooks.pair_gradients the images are not used and may be empty, the views alone); `pairs`
// index `cameras` as (reference, neighbour). `mesh` should be a closed 2-manifold robust in
// floating point (what `reconstruct` writes); its faces stay as they are unless remeshing.
RefineStats RefineMesh(Mesh* mesh, const std::vector<SweepCamera>& cameras,
                       const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                       const RefineHooks& hooks = {});

}  // namespace ms
