// The coordinator's core state: a 3D Delaunay triangulation of the points (CGAL, exact
// predicates), the visibility weights of its cells, and the set O of "outside" cells whose
// boundary is the manifold surface (paper section 2.1 and 2.3, docs/design/manifold.md).
//
//   DelaunayManifold manifold(cameras, options);
//   manifold.Build(points);              // Delaunay, ray tracing, growing
//   Mesh mesh = manifold.ExtractSurface();
//   manifold.Insert(new_points);         // shrink, insert or discard, regrow
//
// CGAL types stay inside manifold/'s internal headers and .cc files (see manifold_impl.h).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "manifold/manifold_options.h"
#include "mesh/mesh.h"

namespace ms {

// A camera as the manifold needs it: where it is and how it looks (for the ray index).
struct ManifoldCamera {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // world -> camera
  // Normalised image-coordinate extent of the camera's view (x/z, y/z), e.g. from intrinsics.
  double u_min = -1, u_max = 1, v_min = -1, v_max = 1;
  // A pixel's footprint per unit of depth (1 / focal length in pixels); 0 = unknown.
  double pixel_angle = 0;
};

// A point and the cameras that see it (its viewing rays run camera centre -> point).
struct RayPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  std::vector<int32_t> cameras;
};

struct BuildStats {
  int64_t points = 0;             // input points
  int64_t merged_duplicates = 0;  // at, or nearer than the merge tolerance to, an earlier point
  int64_t steiner_points = 0;
  int64_t graded_steiner_points = 0;  // of which in the empty space (steiner_points.h)
  int64_t vertices = 0, cells = 0;
  int64_t rays = 0, ray_cell_steps = 0;
  int64_t free_cells = 0, outside_cells = 0;
  int64_t free_cells_left_inside = 0;  // free but not in O: refused by the manifold test
  int64_t camera_stars_completed = 0;  // as InsertionStats's, after growing
  int64_t pockets_joined = 0;          // as InsertionStats's
  int64_t slivers_joined = 0;          // as InsertionStats's
  // Manifold tests while growing: all, those the fast (V,E,F) test could not decide, and the
  // surface edges walked by the full test.
  int64_t manifold_tests = 0, full_manifold_tests = 0, link_steps = 0;
  double seconds_triangulation = 0, seconds_ray_tracing = 0, seconds_growing = 0;
};

struct InsertionStats {
  int64_t requested = 0;
  int64_t inserted = 0;
  int64_t discarded_conflict = 0;   // D still met O after shrinking (the paper's rule)
  int64_t discarded_duplicate = 0;  // at (or within the merge tolerance of) an existing vertex
  int64_t gained_rays = 0;          // cameras of those duplicates their vertex did not have
  int64_t discarded_outside = 0;    // outside the Steiner box
  int64_t shrunk_cells =
      0;  // cells removed from O while shrinking (for inserted and discarded points)
  int64_t candidate_rays = 0;  // rays found near conflict regions (with repeats)
  int64_t rewalked_rays = 0;   // old rays walked again to count them on new cells
  int64_t rewalk_steps = 0;    // cells those walks crossed (from their first hole box on)
  int64_t new_rays = 0;
  int64_t outside_cells = 0;  // |O| after regrowing
  // Vertex stars completed to bring a camera left in the matter back into O (regrowing).
  int64_t camera_stars_completed = 0;
  // Joins of free pockets that growing could not enter one cell at a time (whole pockets or a
  // vertex's free cells; --manifold.join-pockets).
  int64_t pockets_joined = 0;
  // Matter cells crossed by no ray that joined with a pocket, which they alone kept out of O by
  // pinching one of its vertices (GrowShrink::FlipAllOrFindSlivers; pocket joins and camera
  // repairs).
  int64_t slivers_joined = 0;
  double seconds_insertion = 0, seconds_growing = 0;
};

struct SurfaceInfo {
  // For every mesh vertex: the id of the input point it is (>= 0), or -1 - k for Steiner
  // point k.
  std::vector<int32_t> vertex_ids;
  int64_t steiner_vertices = 0;  // mesh vertices that are Steiner points
};

// The reconstructed surface proper: the faces of `mesh` (from ExtractSurface with `info`) none
// of whose vertices is a Steiner point, unreferenced vertices removed. The Steiner faces close
// the surface around the free space the cameras saw; they are not an estimate of the scene, so
// they are neither swept nor evaluated. The result is a manifold with boundary.
Mesh SurfaceWithoutSteinerFaces(const Mesh& mesh, const SurfaceInfo& info);
// One flag per mesh vertex: 1 for a Steiner point.
std::vector<uint8_t> SteinerFlags(const SurfaceInfo& info);

class DelaunayManifold {
 public:
  // The implementation, with the CGAL triangulation: manifold/manifold_impl.h, a header of this
  // folder's .cc files (and of the test hooks, testing/manifold_test_hooks.cc) only.
  class Impl;

  DelaunayManifold(std::vector<ManifoldCamera> cameras, const ManifoldOptions& options);
  ~DelaunayManifold();
  DelaunayManifold(const DelaunayManifold&) = delete;
  DelaunayManifold& operator=(const DelaunayManifold&) = delete;

  // Steps (1)-(3) of the paper: Delaunay triangulation of the points and the Steiner points,
  // visibility ray tracing and weighting, growing of O from the heaviest free cell.
  // Point ids are their indices in `points`, which are let go once their rays are traced (pass
  // them with std::move where memory counts). Throws InputError for a camera index out of
  // range or non-finite input; may be called once.
  BuildStats Build(std::vector<RayPoint> points);

  // Incremental refinement (section 2.3): for each point in order, shrink O around its
  // conflict region, discard it if the region still meets O, otherwise insert it and update
  // the weights of the new cells exactly. Then regrow O from its boundary. New point ids
  // continue after the existing ones. With --manifold.insertion rebuild, the points outside
  // the Steiner box are discarded and Build runs again on every point so far (merging
  // near-duplicates as Build does); no point is discarded for a conflict.
  InsertionStats Insert(const std::vector<RayPoint>& points);

  // Insert in pieces, for a caller that receives a batch in order (the coordinator inserts the
  // points of the cameras whose results are in while later cameras are still being swept):
  // BeginInsert(); InsertPart(a); InsertPart(b); FinishInsert() does exactly what Insert(a then
  // b) does, the re-walks, new rays and regrowing waiting for FinishInsert. Each part is checked
  // as Insert checks its points; calls out of that order are programming errors (MS_CHECK).
  void BeginInsert();
  void InsertPart(const std::vector<RayPoint>& points);
  InsertionStats FinishInsert();

  // Threads that walk viewing rays in Build and Insert (0, the default: one per core). The
  // results do not depend on it.
  void set_walk_threads(int threads);

  // The surface between O and the rest, normals towards O (free space). Deterministic:
  // vertices ordered by point id, faces sorted.
  Mesh ExtractSurface(SurfaceInfo* info = nullptr) const;

  // The boundary of every free cell (weight at least t_w), in O or not, normals towards free
  // space: the surface the visibility alone gives, before growing keeps it manifold. Generally
  // not a manifold; for diagnosis (`manifold --free-space-boundary`). Ordered as
  // ExtractSurface.
  Mesh ExtractFreeSpaceBoundary() const;

  // Full validity check: triangulation valid, no infinite cell in O, bookkeeping consistent,
  // every vertex regular (the surface is a closed 2-manifold), if check_weights the ray counts
  // of every cell equal a recomputation from scratch, and with the paper's regrowing
  // (--manifold.regrow-seeds boundary) O is maximal: no free cell sharing a face with O could
  // join it keeping the surface manifold. Returns "" if valid.
  std::string Validate(bool check_weights = true) const;

  // Every point so far (by id) with the cameras of its rays, sorted: what a manifold built anew
  // from the same points starts from (`manisweep extend` rebuilds with its new points).
  std::vector<RayPoint> Points() const;

  int64_t num_points() const;    // input points so far (ids 0..num_points-1)
  int64_t num_vertices() const;  // finite vertices incl. Steiner
  int64_t num_cells() const;     // finite cells
  int64_t num_outside_cells() const;
  // Free cells sharing a face with O that could join O keeping the surface manifold: 0 when O
  // is maximal (always after Build, and after Insert with --manifold.regrow-seeds boundary).
  int64_t num_joinable_cells() const;
  // Free cells not in O (refused by the manifold test or unreachable). Scans every cell, so
  // Insert, whose cost should follow the batch, does not report it; Build does.
  int64_t num_free_cells_inside() const;
  // Cameras whose centre lies in no cell of O: a camera stands in free space, so from such a
  // camera the surface is seen from inside the matter (docs/design/manifold.md, "Known limits").
  // Locates only cameras whose start cell an insertion destroyed.
  std::vector<int32_t> CamerasInMatter();
  size_t MemoryBytes() const;  // estimate of the triangulation + ray data

 private:
  // --manifold.insertion rebuild: every point so far and the open batch (manifold_impl.h).
  struct Rebuild;
  void RebuildBegin();
  void RebuildAppend(const std::vector<RayPoint>& points);
  InsertionStats RebuildFinish();

  std::unique_ptr<Impl> impl_;
  std::unique_ptr<Rebuild> rebuild_;  // null with incremental insertion
};

}  // namespace ms
