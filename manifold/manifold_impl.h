// DelaunayManifold's state and its steps (paper sections 2.1 and 2.3, docs/design/manifold.md).
// Internal to manifold/ (and the test hooks, manifold_test_hooks.cc): it names CGAL types.
//
// The pieces it combines, bottom up:
//   triangulation.h    CGAL's Delaunay triangulation, VertexInfo and CellInfo
//   cell_predicates.h  stateless exact predicates on a cell and a segment
//   cell_labels.h      weights, free space, the set O and its per-vertex counts
//   ray_walker.h       viewing rays through the triangulation (visit stamps, camera starts)
//   parallel_walks.h   many rays walked on all cores, their crossings counted
//   regularity.h       does the surface stay a 2-manifold when a cell flips?
//   grow_shrink.h      growing and shrinking O
// Build and Insert (delaunay_manifold.cc) are short lists of named steps over these;
// Validate (manifold_validate.cc) checks them layer by layer.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "manifold/batch_rays.h"
#include "manifold/cell_labels.h"
#include "manifold/delaunay_manifold.h"
#include "manifold/grow_shrink.h"
#include "manifold/manifold_options.h"
#include "manifold/parallel_walks.h"
#include "manifold/point_merging.h"
#include "manifold/ray_index.h"
#include "manifold/ray_walker.h"
#include "manifold/regularity.h"
#include "manifold/steiner_points.h"
#include "manifold/triangulation.h"

namespace ms {

// The Steiner box test of incremental insertion and of rebuilds (against the first box).
inline bool StrictlyInsideBox(const Eigen::Vector3d& position, const Eigen::Vector3d& box_min,
                              const Eigen::Vector3d& box_max) {
  return (position.array() > box_min.array()).all() && (position.array() < box_max.array()).all();
}

class DelaunayManifold::Impl {
 public:
  using Delaunay = manifold_detail::Delaunay;
  using Cell_handle = manifold_detail::Cell_handle;
  using Vertex_handle = manifold_detail::Vertex_handle;
  using Point = manifold_detail::Point;

  Impl(std::vector<ManifoldCamera> cameras, const ManifoldOptions& options);

  BuildStats Build(std::vector<RayPoint> points);
  InsertionStats Insert(const std::vector<RayPoint>& points);
  void BeginInsert();
  void InsertPart(const std::vector<RayPoint>& points);
  InsertionStats FinishInsert();
  Mesh ExtractSurface(SurfaceInfo* info) const;
  Mesh ExtractFreeSpaceBoundary() const;
  // Not const, unlike DelaunayManifold::Validate: the weight layer walks every ray again,
  // which takes visit stamps and the walker's scratch buffers. The state checked is unchanged.
  std::string Validate(bool check_weights);

  int64_t num_points() const { return static_cast<int64_t>(positions_.size()); }
  std::vector<RayPoint> Points() const {
    std::vector<RayPoint> points(positions_.size());
    for (size_t i = 0; i < positions_.size(); ++i) points[i].position = positions_[i];
    ray_index_->ForEachInDirectionOrder(
        [&](const RayRef& ray) { points[ray.point].cameras.push_back(ray.camera); });
    for (RayPoint& p : points) std::sort(p.cameras.begin(), p.cameras.end());
    return points;
  }
  bool built() const { return built_; }
  void set_walk_threads(int threads) { walks_.set_threads(threads); }
  int walk_threads() const { return walks_.threads(); }
  const std::vector<ManifoldCamera>& cameras() const { return cameras_; }
  const ManifoldOptions& options() const { return options_; }
  int64_t num_vertices() const { return static_cast<int64_t>(dt_.number_of_vertices()); }
  int64_t num_cells() const { return static_cast<int64_t>(dt_.number_of_finite_cells()); }
  int64_t num_outside_cells() const { return labels_.outside_count(); }
  // Free cells next to O that could join it (a scan with the manifold test on each).
  int64_t CountJoinableCells() { return grow_shrink_.CountJoinableCells(nullptr, 0); }
  // Free cells that growing left out of O (refused by the manifold test or unreachable).
  int64_t CountFreeCellsInside() const {
    int64_t n = 0;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      n += labels_.FreeOutsideO(c);
    }
    return n;
  }
  // Completes vertex stars until no camera with a free start cell is left in the matter;
  // returns how many. `boundary`: every free cell next to O with its refusal, as a Grow from
  // all of them leaves it (GrowShrink::Refusals), so that growing on after a star costs what
  // the star changed; null: growing on starts from a scan of all cells.
  int64_t FreeEnclosedCameras(manifold_detail::GrowShrink::Refusals* boundary);
  // Joins the pockets of free space next to O (from the cells BoundarySeeds(which, changed_in)
  // gives) that growing could not enter, and grows on from them; returns the joins. With
  // `pinch_rounds` > 0 a pocket may take the small matter pieces that pinch it (after an
  // insertion only: --manifold.pocket-pinch-rounds). `boundary` as for FreeEnclosedCameras: the
  // last growing then starts from what changed.
  int64_t JoinFreePockets(RegrowSeeds which, uint32_t changed_in, int pinch_rounds,
                          manifold_detail::GrowShrink::Refusals* boundary = nullptr);
  void LogCameraStars(int64_t completed) const;
  // Cameras none of whose start cells is in O (manifold.h).
  std::vector<int32_t> CamerasInMatter() {
    std::vector<int32_t> enclosed;
    for (int32_t camera = 0; camera < static_cast<int32_t>(cameras_.size()); ++camera) {
      const std::vector<Cell_handle> cells = walker_.StartCandidates(walker_.StartOf(camera));
      if (std::none_of(cells.begin(), cells.end(),
                       [&](const Cell_handle& c) { return labels_.InO(c); })) {
        enclosed.push_back(camera);
      }
    }
    return enclosed;
  }
  size_t MemoryBytes() const {
    return dt_.number_of_cells() * sizeof(Delaunay::Cell) +
           dt_.number_of_vertices() * sizeof(Delaunay::Vertex) +
           positions_.capacity() * sizeof(Eigen::Vector3d) +
           vertex_of_point_.capacity() * sizeof(Vertex_handle) + ray_index_->MemoryBytes();
  }

  // The state and the steps below are the implementation's own; the test hooks
  // (testing/manifold_test_hooks.cc) also reach them, to build states no public call makes.

  // One Insert call's state, shared by its steps. A batch is inserted in one or more parts
  // (InsertPart). The exact recount of the cells born in the batch is done ray by ray once no
  // part has marked the ray for kRecountLag parts, and for the rest at the end (FinishInsert):
  // a coordinator inserting parts while its sweep runs is left with little of it, and a ray
  // near the holes of several consecutive parts is walked once for all of them.
  struct InsertionBatch {
    uint32_t number = 0;              // vertices changed in the batch carry it (for regrowing)
    uint32_t first_part = 0;          // parts first_part, first_part + 1, ...: cells carry theirs
    uint32_t part = 0;                // the current part (CellInfo::born of the cells it makes)
    int32_t first_new_id = 0;         // id of the current part's first inserted point
    size_t first_new_ray = 0;         // id of the batch's first new ray in the index
    manifold_detail::BatchRays rays;  // what the batch knows of each ray in the index
    // The rays each part marked (by part - first_part); a ray is walked from the bucket of the
    // last part that marked it.
    std::vector<std::vector<RayRef>> marked_in;
    bool all_affected = false;  // every ray is walked from its camera on, at the end
    // Slack for the segment/box test: rounding in the box and the clipping, scene-relative.
    double box_slack = 0;
    Cell_handle hint;  // where locating the next point starts
    // The current point's conflict region D and the facets on its boundary.
    std::vector<Cell_handle> conflicts;
    std::vector<manifold_detail::Facet> boundary;
    // The cameras of the current part's points (from first_new_id on), sorted, until their
    // rays join the index at the end of the part; older points' cameras are their rays there.
    std::vector<std::vector<int32_t>> part_cameras;
    // Cameras of duplicate points that the vertex they duplicate gains: (point id, camera).
    std::vector<std::pair<int32_t, int32_t>> gained_rays;
    std::vector<RayRef> candidates;   // scratch of MarkRaysNear
    std::vector<Cell_handle> around;  // scratch of InsertPoint
  };

  // --- Build steps ---
  // Bounding box of the points and cameras; throws InputError for bad input.
  void CheckAndBound(const std::vector<RayPoint>& points, Eigen::Vector3d* lo,
                     Eigen::Vector3d* hi) const;
  // Steiner points around [lo, hi]; decides graded Steiner points and sets the Steiner box.
  SteinerPoints PlaceSteinerPoints(const std::vector<RayPoint>& points, const Eigen::Vector3d& lo,
                                   const Eigen::Vector3d& hi, BuildStats* stats);
  // (1) Delaunay triangulation of the Steiner points and the points.
  void Triangulate(const std::vector<RayPoint>& points, const std::vector<Eigen::Vector3d>& steiner,
                   BuildStats* stats);
  // (2) Every viewing ray walked and counted on the cells it crosses.
  void TraceRays(const std::vector<RayPoint>& points, BuildStats* stats);
  // (2b) With behind_ratio > 0: every ray counted on the cell it enters past its point.
  void CountRaysBehind();
  // (2c) With --manifold.visibility cut: every cell's free-space verdict from a minimum cut of
  // the cell graph (free_space_cut.cc).
  void CutFreeSpace();
  // (3) O grown from the heaviest free cell.
  void GrowInitial(BuildStats* stats);

  // --- Insert steps ---
  // Throws InputError for a non-finite point or a camera out of range.
  void CheckNewPoints(const std::vector<RayPoint>& points) const;
  // Strictly inside the Steiner box (a new point elsewhere is discarded).
  bool InSteinerBox(const Eigen::Vector3d& position) const {
    return StrictlyInsideBox(position, box_min_, box_max_);
  }
  InsertionBatch StartBatch();
  // One new point: discarded, or O shrunk around it and the point inserted.
  void InsertOne(const RayPoint& point, InsertionBatch* batch, InsertionStats* stats);
  // D, the cells in conflict with p (batch->conflicts, batch->boundary), from *located.
  // Returns false, having counted the discard, for a point outside the Steiner box or the
  // triangulation or on an existing vertex.
  bool FindConflictRegion(const RayPoint& point, const Point& p, InsertionBatch* batch,
                          Cell_handle* located, InsertionStats* stats);
  // Shrinks O around D; false if D still meets O (the point is then discarded).
  bool ShrinkAround(const InsertionBatch& batch, InsertionStats* stats);
  // Lowers the reach of the rays that may cross D and marks them (for RewalkMarked).
  void MarkRaysNear(InsertionBatch* batch, InsertionStats* stats);
  // Replaces D by the star of the new point; the new cells are born in the current part.
  void InsertPoint(const Point& p, const RayPoint& point, InsertionBatch* batch,
                   InsertionStats* stats);
  // Exact ray counts on the cells born in the batch: each marked ray walked again and counted
  // on the cells born since its last walk (RewalkMarked: at the end of a part, the rays last
  // marked kRecountLag parts ago; at the end of the batch, all that are left), and the new
  // points' rays, counted everywhere and filed in the index at the end of their part.
  static constexpr uint32_t kRecountLag = 8;
  void EndPart(InsertionBatch* batch, InsertionStats* stats);
  void RewalkMarked(InsertionBatch* batch, uint32_t last_marked_by, InsertionStats* stats);
  void RewalkAll(InsertionBatch* batch, InsertionStats* stats);
  // Walks `rays` again on all cores, each with its reach (RewalkRay; none: every ray from its
  // camera), and counts them.
  void Rewalk(const InsertionBatch& batch, const std::vector<RayRef>& rays,
              const std::vector<float>& reach, InsertionStats* stats);
  // One ray of Rewalk: records its crossings of the cells born since its last walk (the cells
  // that have it counted already, or whose geometry did not change, are left out); returns the
  // cells stepped through.
  template <typename Marks, typename Record>
  int64_t RewalkRay(const InsertionBatch& batch, const RayRef& ray, float reach, Marks& marks,
                    manifold_detail::WalkScratch& scratch, Record& record) const;
  void TraceNewRays(InsertionBatch* batch, InsertionStats* stats);
  void GainCameras(const Vertex_handle& vertex, const std::vector<int32_t>& cameras,
                   InsertionBatch* batch);
  // With behind_ratio > 0, at the end of a batch: its new rays counted on the cells they enter
  // past their point, and the older rays that end at a vertex the batch changed on theirs if
  // it was born in the batch (a cell behind that survived the batch has its rays counted).
  void CountRaysBehindAfterBatch(const InsertionBatch& batch);
  // The cell `ray` enters past its point (CellBehind); `star` is scratch.
  Cell_handle CellBehindRay(const RayRef& ray, std::vector<Cell_handle>* star) const;
  // Regrows O from its boundary where the batch changed something, frees cameras left in the
  // matter and joins pockets (stats->camera_stars_completed, stats->pockets_joined).
  void Regrow(const InsertionBatch& batch, InsertionStats* stats);

  // --- Validate layers (manifold_validate.cc), each run only when the one before passed ---
  std::string ValidateTriangulation() const;  // CGAL's own check
  std::string ValidateLabels() const;         // O and the per-vertex counts
  std::string ValidateManifold();             // every vertex regular
  std::string ValidateWeights();              // ray counts against a recount from scratch
  std::string ValidateMaximal();              // no free cell next to O could join it

  ManifoldOptions options_;
  std::vector<ManifoldCamera> cameras_;
  Delaunay dt_;
  manifold_detail::CellLabels labels_{dt_, options_};
  manifold_detail::Regularity regularity_{dt_};
  manifold_detail::RayWalker walker_;
  manifold_detail::ParallelWalks walks_{&walker_, &labels_};  // one thread per core
  manifold_detail::GrowShrink grow_shrink_{dt_, options_, labels_, regularity_};
  std::unique_ptr<RayIndex> ray_index_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<Vertex_handle> vertex_of_point_;
  Eigen::Vector3d box_min_, box_max_;  // Steiner box: points outside are discarded
  MergeTolerance merge_;               // near-duplicate input points (set by Build)
  MergeTolerance new_point_merge_;     // near-duplicate new points (set by Build)
  uint32_t batch_ = 0;                 // insertion batches so far
  uint32_t parts_ = 0;                 // insertion parts so far (CellInfo::born)
  // The batch between BeginInsert and FinishInsert, and what its parts counted so far.
  std::optional<InsertionBatch> open_batch_;
  InsertionStats open_stats_;
  bool built_ = false;
};

// What --manifold.insertion rebuild keeps between batches: a new Impl, with the cameras,
// options and threads of the last, is built from `points` (the built ones and every batch's, in
// order, so point ids are as incremental insertion's).
struct DelaunayManifold::Rebuild {
  std::vector<RayPoint> points;
  // The first build's Steiner box. New points outside it are discarded: each rebuild's box
  // grows with its points, so filtering against the latest one would let it creep outwards.
  Eigen::Vector3d box_min, box_max;
  int64_t merged_duplicates = 0;  // of the last build
  bool open = false;              // between BeginInsert and FinishInsert
  InsertionStats stats;           // of the open batch
  size_t batch_begin = 0;         // index in points of the open batch's first point
};

}  // namespace ms
