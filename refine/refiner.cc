#include "refine/refiner.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "base/log.h"
#include "base/parallel_for.h"
#include "mesh/float_robustness.h"
#include "refine/gradient_kernel.h"
#include "refine/mesh_moves.h"
#include "refine/pair_sampling.h"
#include "refine/photometric_gradient.h"
#include "refine/remesh.h"

namespace ms {
namespace {

// The finest level: images halved until their longest side fits max_image_dimension.
int FinestLevel(const std::vector<SweepCamera>& cameras, const RefineOptions& options) {
  int longest = 0;
  for (const SweepCamera& c : cameras) {
    longest = std::max({longest, c.view.intrinsics.width, c.view.intrinsics.height});
  }
  return PyramidLevelToFit(longest, options.max_image_dimension);
}

// The gradient of all pairs, summed in pair order whoever computed them (this process's
// threads, or workers through `source`).
PairGradient SumPairs(const Mesh& mesh, const std::vector<RefineView>& views, int level,
                      const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                      const PairGradientSource& source, PairGradientKernel* kernel) {
  std::vector<PairGradient> per_pair(pairs.size());
  if (source) {
    if (!source(mesh, level, &per_pair)) throw RefineInterrupted();
    if (per_pair.size() != pairs.size()) {
      throw InternalError(
          fmt::format("refine: {} pair gradients for {} pairs", per_pair.size(), pairs.size()));
    }
  } else {
    ParallelFor(
        pairs.size(),
        [&](size_t i) {
          per_pair[i] =
              kernel->Compute(mesh, views[pairs[i].first], views[pairs[i].second], options);
        },
        kernel->ThreadSafe() ? options.threads : 1);
  }
  PairGradient total;
  total.Resize(mesh.vertices.size());
  for (const PairGradient& g : per_pair) total.Add(g);
  return total;
}

// The longest move a vertex may make in one step: max_step_px pixels of reprojection shift at
// this vertex, as a depth change (sqrt(W / H) per pixel), times `scale`; none where no image
// moves it (H = 0).
double StepLimit(const PairGradient& data, size_t v, const RefineOptions& options, double scale) {
  const double h = data.parallax_rate2[v];
  return h > 0 ? scale * options.max_step_px * std::sqrt(data.weight[v] / h) : 0;
}

Eigen::Vector3d CappedAt(const Eigen::Vector3d& d, double limit) {
  const double length = d.norm();
  return length > limit ? Eigen::Vector3d(d * (limit / length)) : d;
}

// The step of docs/design/refine.md: -step x g / H per vertex (a Gauss-Newton scale), at most
// max_step_px pixels of reprojection shift, plus the thin plate's -smoothness x dE_s/dv; all
// times `scale` (backtracking, in (0, 1]). The thin plate moves only vertices the images move
// (H > 0): alone it shrinks what no camera sees, such as the closed mesh's matter above the
// cameras, and once remeshing has cut that into small faces it swept them onto the cameras.
std::vector<Eigen::Vector3d> Displacements(const Mesh& mesh, const PairGradient& data,
                                           const std::vector<std::vector<int32_t>>& neighbours,
                                           const std::vector<uint8_t>& stuck,
                                           const RefineOptions& options, double scale) {
  std::vector<Eigen::Vector3d> move(mesh.vertices.size(), Eigen::Vector3d::Zero());
  const double sigma2 = options.gaussian_sigma_px * options.gaussian_sigma_px;
  for (size_t v = 0; v < move.size(); ++v) {
    const double h = data.parallax_rate2[v];
    if (!(h > 0)) continue;
    const Eigen::Vector3d d = -scale * options.step * sigma2 * data.gradient[v] / h;
    move[v] = CappedAt(d, StepLimit(data, v, options, scale));
  }
  if (options.smoothness > 0) {
    const std::vector<Eigen::Vector3d> thin_plate = ThinPlateGradient(mesh, neighbours);
    for (size_t v = 0; v < move.size(); ++v) {
      if (data.parallax_rate2[v] > 0) move[v] -= scale * options.smoothness * thin_plate[v];
    }
  }
  // A vertex whose last move was refused sits in a fold the images keep pushing it into: it
  // moves towards its neighbours' mean instead, which opens the fold.
  if (options.unfold > 0) {
    const std::vector<Eigen::Vector3d> unfold =
        UnfoldingMoves(mesh, neighbours, stuck, options.unfold);
    for (size_t v = 0; v < stuck.size(); ++v) {
      if (stuck[v]) move[v] = CappedAt(unfold[v], StepLimit(data, v, options, scale));
    }
  }
  return move;
}

// 1% of the median depth of the mesh's vertices in front of a camera (ten times its near plane),
// the smallest over the cameras.
double CameraClearance(const Mesh& mesh, const std::vector<SweepCamera>& cameras) {
  double clearance = std::numeric_limits<double>::infinity();
  for (const SweepCamera& c : cameras) {
    clearance = std::min(clearance, 10 * RefineNearPlane(mesh, c.view));
  }
  return std::isfinite(clearance) ? clearance : 0;
}

// The size of a pixel at x (scene units) in the camera that sees it finest: the smallest
// z / f over the views x projects into; +infinity where none does.
double Footprint(const std::vector<RefineView>& views, const Eigen::Vector3d& x) {
  double best = std::numeric_limits<double>::infinity();
  for (const RefineView& v : views) {
    const Eigen::Vector3d y = v.view.ToCamera(x);
    if (!(y.z() > 0)) continue;
    const Intrinsics& k = v.view.intrinsics;
    const double u = k.fx * y.x() / y.z() + k.cx, w = k.fy * y.y() / y.z() + k.cy;
    if (u < 0 || w < 0 || u > k.width || w > k.height) continue;
    best = std::min(best, y.z() / std::max(k.fx, k.fy));
  }
  return best;
}

// Where each camera centre stands with respect to a closed mesh: its winding number (1 or -1
// inside, 0 outside) and its distance to the nearest face.
struct CameraSide {
  int winding = 0;
  double distance = std::numeric_limits<double>::infinity();
};

std::vector<CameraSide> CameraSides(const Mesh& mesh, const std::vector<Eigen::Vector3d>& centres) {
  std::vector<CameraSide> sides(centres.size());
  ParallelFor(centres.size(), [&](size_t c) {
    const Eigen::Vector3d& p = centres[c];
    double solid_angle = 0;  // Van Oosterom and Strackee, summed over the faces
    for (const auto& f : mesh.faces) {
      const std::array<Eigen::Vector3d, 3> t = {mesh.vertices[f[0]], mesh.vertices[f[1]],
                                                mesh.vertices[f[2]]};
      const Eigen::Vector3d a = t[0] - p, b = t[1] - p, d = t[2] - p;
      const double la = a.norm(), lb = b.norm(), ld = d.norm();
      solid_angle += 2 * std::atan2(a.dot(b.cross(d)),
                                    la * lb * ld + a.dot(b) * ld + b.dot(d) * la + d.dot(a) * lb);
      sides[c].distance = std::min(sides[c].distance, (p - ClosestPointOnTriangle(p, t)).norm());
    }
    sides[c].winding = static_cast<int>(std::lround(solid_angle / (4 * M_PI)));
  });
  return sides;
}

// The vertices of the faces that pass within `radius` of one of `centres`. Remeshing leaves those
// faces as they are: a surface that near a camera is one the moves keep clear of it, not one with
// detail to add, and the pixel footprint there shrinks with the distance, so splits would follow
// it down towards nothing.
std::vector<uint8_t> VerticesNearCameras(const Mesh& mesh,
                                         const std::vector<Eigen::Vector3d>& centres,
                                         double radius) {
  std::vector<uint8_t> near_face(mesh.faces.size(), 0);
  ParallelFor(mesh.faces.size(), [&](size_t f) {
    const std::array<Eigen::Vector3d, 3> t = {mesh.vertices[mesh.faces[f][0]],
                                              mesh.vertices[mesh.faces[f][1]],
                                              mesh.vertices[mesh.faces[f][2]]};
    const Eigen::Vector3d middle = (t[0] + t[1] + t[2]) / 3;
    double reach = 0;  // of the face from its middle
    for (const Eigen::Vector3d& x : t) reach = std::max(reach, (x - middle).norm());
    for (const Eigen::Vector3d& c : centres) {
      if ((c - middle).norm() - reach >= radius) continue;  // too far for any point of the face
      if ((c - ClosestPointOnTriangle(c, t)).norm() < radius) {
        near_face[f] = 1;
        break;
      }
    }
  });
  std::vector<uint8_t> frozen(mesh.vertices.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!near_face[f]) continue;
    for (int32_t v : mesh.faces[f]) frozen[v] = 1;
  }
  return frozen;
}

// Remeshing at the start of a level (docs/design/refine.md "Remeshing"): collapses, splits, flips,
// with edge lengths in pixels of `views`, none of them within `keep_out` of a camera centre.
void Remesh(Mesh* mesh, const std::vector<RefineView>& views, const RefineOptions& options,
            const MoveOptions& move_options, double keep_out, RefineStats* stats) {
  const double tolerance = move_options.tolerance;
  // Found again before each step: collapses renumber the vertices, splits add some.
  const auto frozen = [&] { return VerticesNearCameras(*mesh, move_options.keep_clear, keep_out); };
  if (options.min_edge_px > 0) {
    const CollapseStats collapse = CollapseShortEdges(
        mesh,
        [&](const Eigen::Vector3d& x) {
          // Where no camera sees the surface (its footprint is infinite), nothing is collapsed:
          // collapses there would reshape matter no image supports, up to crossing a camera.
          const double footprint = Footprint(views, x);
          return std::isfinite(footprint) ? options.min_edge_px * footprint : 0.0;
        },
        options.max_face_turn_deg, tolerance, frozen());
    stats->collapses += collapse.collapses;
    stats->collapses_refused += collapse.refused;
  }
  const SplitStats split = SplitLongEdges(
      mesh, [&](const Eigen::Vector3d& x) { return options.max_edge_px * Footprint(views, x); },
      options.max_vertices, tolerance, frozen());
  stats->splits += split.splits;
  stats->splits_refused += split.refused;
  if (options.flip_dihedral_deg > 0) {
    const FlipStats flip = FlipEdges(mesh, options.flip_dihedral_deg, tolerance, frozen());
    stats->flips += flip.flips;
    stats->flips_refused += flip.refused;
  }
}

// The remeshing counters of `made` added to `stats`.
void AddRemeshCounts(const RefineStats& made, RefineStats* stats) {
  stats->collapses += made.collapses;
  stats->collapses_refused += made.collapses_refused;
  stats->splits += made.splits;
  stats->splits_refused += made.splits_refused;
  stats->flips += made.flips;
  stats->flips_refused += made.flips_refused;
}

// Remeshing as above, kept only where it keeps the cameras where they were. Collapses and flips
// move the surface a little, and are checked for self-intersections but not against the cameras:
// where a camera changed sides of the mesh, or the surface came nearer to it than the moves'
// clearance (and nearer than before), the attempt is undone (a camera inside the matter sees
// nothing but the inside of a face). Remeshing leaves the faces within twice the clearance of a
// camera alone, so a surface that already passes that near one (a swept mesh may) does not stop
// the level's remeshing elsewhere; the attempts after the first leave a wider zone alone, then
// split only, then keep the mesh.
void RemeshKeepingCameras(Mesh* mesh, const std::vector<RefineView>& views,
                          const RefineOptions& options, const MoveOptions& move_options, int level,
                          RefineStats* stats) {
  const Timer timer;
  const std::vector<CameraSide> before = CameraSides(*mesh, move_options.keep_clear);
  const Mesh kept = *mesh;
  RefineOptions splits_only = options;
  splits_only.min_edge_px = 0;
  splits_only.flip_dihedral_deg = 0;
  struct Attempt {
    const RefineOptions* options;
    double keep_out;  // in clearances
    const char* what;
  };
  const Attempt attempts[] = {{&options, 2, "remeshing"},
                              {&options, 8, "remeshing further from the cameras"},
                              {&splits_only, 8, "splitting alone"}};
  for (const Attempt& attempt : attempts) {
    RefineStats made;
    Remesh(mesh, views, *attempt.options, move_options, attempt.keep_out * move_options.clearance,
           &made);
    const std::vector<CameraSide> after = CameraSides(*mesh, move_options.keep_clear);
    size_t c = 0;
    while (
        c < after.size() && after[c].winding == before[c].winding &&
        (after[c].distance >= move_options.clearance || after[c].distance >= before[c].distance)) {
      ++c;
    }
    if (c == after.size()) {
      AddRemeshCounts(made, stats);
      spdlog::info("refine: level {} {}: {} vertices, {} split, {} collapsed, {} flipped; {:.1f} s",
                   level, attempt.what, mesh->vertices.size(), made.splits, made.collapses,
                   made.flips, timer.Seconds());
      return;
    }
    spdlog::warn("refine: {} at level {} put camera {} {} the mesh ({:.3g} from it); undone",
                 attempt.what, level, c,
                 after[c].winding == before[c].winding ? "too near" : "on the other side of",
                 after[c].distance);
    *mesh = kept;
  }
  ++stats->remeshings_undone;
  spdlog::warn("refine: level {} keeps the mesh unremeshed", level);
}

}  // namespace

RefineView RefineViewAtLevel(const SweepCamera& camera, int level) {
  const SweepCamera scaled = CameraAtPyramidLevel(camera, level);
  RefineView out;
  out.camera = scaled.id;
  out.view = scaled.view;
  scaled.image.convertTo(out.image, CV_64F);
  return out;
}

std::vector<std::pair<int, int>> RefinePairs(const Scene& scene, const NeighbourOptions& options) {
  std::vector<std::pair<int, int>> pairs;
  for (int c = 0; c < static_cast<int>(scene.views.size()); ++c) {
    for (int n : SelectNeighbours(scene, c, options)) pairs.emplace_back(c, n);
  }
  return pairs;
}

namespace {

void CheckRefineInputs(const std::vector<SweepCamera>& cameras,
                       const std::vector<std::pair<int, int>>& pairs, const RefineHooks& hooks) {
  for (const auto& [a, b] : pairs) {
    const int n = static_cast<int>(cameras.size());
    if (a < 0 || a >= n || b < 0 || b >= n || a == b) {
      throw InputError(
          fmt::format("refine: camera pair ({}, {}) out of range ({} cameras)", a, b, n));
    }
  }
  if (hooks.pair_gradients) return;
  for (const SweepCamera& c : cameras) {
    if (c.image.empty()) {
      throw InternalError(fmt::format(
          "refine: camera {} has no image and no pair gradient source was given", c.id));
    }
  }
}

// The safe moves' limits, fixed for the whole refinement (kept by a checkpoint) so that they do
// not drift with the mesh's extent.
MoveOptions SafeMoveOptions(const Mesh& mesh, const std::vector<SweepCamera>& cameras,
                            const RefineOptions& options, const RefineState* resume) {
  MoveOptions move_options;
  // The cleanup's margin over check-mesh's tolerance (mesh/float_cleanup.h).
  move_options.tolerance =
      resume ? resume->tolerance
             : 2 * FloatCheckTolerance(mesh, std::vector<uint8_t>(mesh.faces.size(), 1));
  move_options.max_face_turn_deg = options.max_face_turn_deg;
  move_options.max_halvings = options.max_halvings;
  // The surface keeps away from every camera's centre (CameraClearance): a camera in the
  // matter, or a face inside its near plane, would break its views.
  for (const SweepCamera& c : cameras) move_options.keep_clear.push_back(c.view.Center());
  move_options.clearance = resume ? resume->camera_clearance : CameraClearance(mesh, cameras);
  return move_options;
}

// What the levels of one refinement share.
struct Refinement {
  Mesh* mesh;
  const std::vector<std::pair<int, int>>& pairs;
  const RefineOptions& options;
  const RefineHooks& hooks;
  PairGradientKernel* kernel;  // null: hooks.pair_gradients
  MoveOptions move_options;
  RefineStats* stats;
  int iteration = 0;  // over all levels

  PairGradient Sum(const Mesh& at, const std::vector<RefineView>& views, int level) const {
    return SumPairs(at, views, level, pairs, options, hooks.pair_gradients, kernel);
  }
};

// `count` iterations at one pyramid level (index li from the coarsest), from `resumed` state
// when the refinement was interrupted in this level. The finest level (l == 0) keeps its last
// step only if it lowered the energy.
void RefineLevel(Refinement& r, int li, int l, int level, int count, const RefineState* resumed,
                 const std::vector<RefineView>& views) {
  Mesh* mesh = r.mesh;
  const std::vector<std::vector<int32_t>> neighbours = VertexNeighbours(*mesh);
  // Backtracking: a step that raised the energy is undone and retried at half the length;
  // after a step that lowered it, the length grows back (by 1.25, up to the full step).
  double scale = resumed ? resumed->scale : 1;
  std::vector<Eigen::Vector3d> accepted =
      resumed ? resumed->accepted : std::vector<Eigen::Vector3d>();
  double accepted_energy = resumed ? resumed->accepted_energy : 0;
  std::vector<uint8_t> stuck;  // vertices whose last move was refused
  if (resumed) {
    stuck.assign(mesh->vertices.size(), 0);
    for (int32_t v : resumed->stuck) stuck[v] = 1;
  }
  PairGradient accepted_data;
  if (!accepted.empty()) {  // the gradient there, as the interrupted run had it
    Mesh at_accepted = *mesh;
    at_accepted.vertices = accepted;
    accepted_data = r.Sum(at_accepted, views, level);
  }
  for (int i = resumed ? resumed->iteration_in_level : 0; i < count; ++i) {
    Timer timer;
    PairGradient data = r.Sum(*mesh, views, level);
    RefineIteration it;
    it.level = level;
    it.iteration = ++r.iteration;
    it.vertices = static_cast<int64_t>(r.mesh->vertices.size());
    it.pixels = data.pixels;
    it.energy = data.MeanEnergy();
    if (r.iteration == 1 && data.pixels == 0) {
      throw InputError(
          "refine: no pixel of any camera pair has a defined ZNCC at the first level: no camera "
          "sees the mesh (is it the mesh of this scene?) or the images are textureless there");
    }
    if (!accepted.empty() && it.energy > accepted_energy) {
      it.rejected = true;
      mesh->vertices = accepted;
      data = accepted_data;
      scale /= 2;
    } else {
      if (!accepted.empty()) scale = std::min(1.0, scale * 1.25);
      accepted = mesh->vertices;
      accepted_data = data;
      accepted_energy = it.energy;
    }
    it.step_scale = scale;
    Timer check_timer;
    const MoveStats moved =
        MoveVerticesSafely(mesh, Displacements(*mesh, data, neighbours, stuck, r.options, scale),
                           r.move_options, r.options.unfold > 0 ? &stuck : nullptr);
    it.checks = moved.rounds;
    it.check_seconds = check_timer.Seconds();
    it.moved = moved.moved;
    it.halved = moved.halved;
    it.refused = moved.refused;
    it.largest_move = moved.largest;
    it.seconds = timer.Seconds();
    r.stats->iterations.push_back(it);
    if (r.hooks.progress) r.hooks.progress(it);
    if (r.hooks.checkpoint) {
      RefineState state;
      state.level_index = li;
      state.iteration_in_level = i + 1;
      state.iterations_done = r.iteration;
      state.scale = scale;
      state.accepted_energy = accepted_energy;
      state.accepted = accepted;
      state.tolerance = r.move_options.tolerance;
      state.camera_clearance = r.move_options.clearance;
      for (size_t v = 0; v < stuck.size(); ++v) {
        if (stuck[v]) state.stuck.push_back(static_cast<int32_t>(v));
      }
      r.hooks.checkpoint(*mesh, state);
    }
  }
  if (l == 0 && !accepted.empty()) {
    const double energy = r.Sum(*mesh, views, level).MeanEnergy();
    if (energy > accepted_energy) mesh->vertices = accepted;
    r.stats->final_energy = std::min(energy, accepted_energy);
  }
}

}  // namespace

RefineStats RefineMesh(Mesh* mesh, const std::vector<SweepCamera>& cameras,
                       const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                       const RefineHooks& hooks) {
  const RefineState* resume = hooks.resume;
  options.Check();
  CheckRefineInputs(cameras, pairs, hooks);
  RefineStats stats;
  Timer total;
  if (mesh->faces.empty() || pairs.empty()) return stats;
  std::unique_ptr<PairGradientKernel> kernel;
  if (!hooks.pair_gradients) {
    std::string why;
    kernel = MakePairGradientKernel(options.kernel, &why);
    spdlog::info("refine: gradients by {} ({})", kernel->Name(), why);
  }
  Refinement r{mesh,  pairs,        options,
               hooks, kernel.get(), SafeMoveOptions(*mesh, cameras, options, resume),
               &stats};
  r.iteration = resume ? resume->iterations_done : 0;
  const int finest = FinestLevel(cameras, options);
  const int per_level = options.iterations / options.levels;
  for (int li = 0; li < options.levels; ++li) {
    const int l = options.levels - 1 - li;  // coarsest first
    const int level = finest + l;
    const int count = l == 0 ? options.iterations - per_level * (options.levels - 1) : per_level;
    const bool resumed = resume && li == resume->level_index;
    if (count <= 0 || (resume && li < resume->level_index)) continue;
    std::vector<RefineView> views;
    views.reserve(cameras.size());
    for (const SweepCamera& c : cameras) views.push_back(RefineViewAtLevel(c, level));
    if (options.max_edge_px > 0 && !resumed) {  // a resumed level was remeshed before
      RemeshKeepingCameras(mesh, views, options, r.move_options, level, &stats);
    }
    RefineLevel(r, li, l, level, count, resumed ? resume : nullptr, views);
  }
  stats.seconds = total.Seconds();
  return stats;
}

}  // namespace ms
