// DelaunayManifold: Build and Insert as short lists of named steps over the pieces listed in
// manifold_impl.h, surface extraction, and the public class's forwarding (docs/design/manifold.md).
#include "manifold/delaunay_manifold.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <unordered_set>
#include <utility>

#include "base/check.h"
#include "base/error.h"
#include "base/log.h"
#include "base/memory.h"
#include "manifold/cell_predicates.h"
#include "manifold/manifold_impl.h"
#include "manifold/manifold_vertices.h"
#include "manifold/steiner_sight.h"

namespace ms {

using manifold_detail::BatchRays;
using manifold_detail::CellInfo;
using manifold_detail::GrowShrink;
using manifold_detail::Locate_type;
using manifold_detail::ParallelWalks;
using manifold_detail::SegmentMeetsBox;
using manifold_detail::ToEigen;
using manifold_detail::ToPoint;
using manifold_detail::VertexInfo;
using manifold_detail::WalkScratch;

namespace {

// A point's cameras, sorted, without repeats.
std::vector<int32_t> SortedCameras(std::vector<int32_t> cams) {
  std::sort(cams.begin(), cams.end());
  cams.erase(std::unique(cams.begin(), cams.end()), cams.end());
  return cams;
}

// The face of c opposite its vertex i, as vertex ids in the order that makes the normal point
// into c, rotated so the smallest id leads (keeps orientation): a canonical order.
std::array<int32_t, 3> FaceIntoCell(const manifold_detail::Cell_handle& c, int i) {
  std::array<int32_t, 3> face;
  for (int j = 0; j < 3; ++j) {
    face[j] = c->vertex(manifold_detail::Delaunay::vertex_triple_index(i, j))->info().id;
  }
  std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
  return face;
}

// The mesh of `faces` (by vertex id): the vertices of `used` (sorted by id, each once) in id
// order, the faces sorted. Every face's vertices must be in `used`.
Mesh MeshByIds(const std::vector<std::pair<int32_t, manifold_detail::Vertex_handle>>& used,
               std::vector<std::array<int32_t, 3>> faces) {
  const int32_t lowest = used.empty() ? 0 : used.front().first;
  const int32_t highest = used.empty() ? -1 : used.back().first;
  std::vector<int32_t> index_of(static_cast<size_t>(int64_t{highest} - lowest + 1), -1);
  Mesh mesh;
  mesh.vertices.reserve(used.size());
  for (const auto& [id, v] : used) {
    index_of[id - lowest] = static_cast<int32_t>(mesh.vertices.size());
    mesh.vertices.emplace_back(v->point().x(), v->point().y(), v->point().z());
  }
  std::sort(faces.begin(), faces.end());
  mesh.faces.reserve(faces.size());
  for (const auto& f : faces) {
    std::array<int32_t, 3> face;
    for (int j = 0; j < 3; ++j) {
      face[j] = f[j] >= lowest && f[j] <= highest ? index_of[f[j] - lowest] : -1;
      MS_CHECK(face[j] >= 0) << "vertex " << f[j] << " of a face is not among the mesh's";
    }
    mesh.faces.push_back(face);
  }
  return mesh;
}

}  // namespace

DelaunayManifold::Impl::Impl(std::vector<ManifoldCamera> cameras, const ManifoldOptions& options)
    : options_(options), cameras_(std::move(cameras)), walker_(dt_, cameras_.size()) {
  options_.Check();
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (!cameras_[c].center.allFinite() || !cameras_[c].R.allFinite()) {
      throw InputError("camera " + std::to_string(c) + ": pose is not finite");
    }
  }
  std::vector<RayIndex::Camera> index_cameras;
  for (const ManifoldCamera& c : cameras_) {
    index_cameras.push_back({c.R, c.center, c.u_min, c.u_max, c.v_min, c.v_max});
  }
  ray_index_ = std::make_unique<RayIndex>(std::move(index_cameras));
}

// ---------------------------------------------------------------------------------------------
// Build

BuildStats DelaunayManifold::Impl::Build(std::vector<RayPoint> points) {
  if (built_) throw InternalError("DelaunayManifold::Build called twice");
  built_ = true;
  BuildStats stats;
  stats.points = static_cast<int64_t>(points.size());
  Timer timer;
  Eigen::Vector3d lo, hi;
  CheckAndBound(points, &lo, &hi);
  const SteinerPoints steiner = PlaceSteinerPoints(points, lo, hi, &stats);
  merge_ = InputMergeTolerance(steiner.points, options_);
  new_point_merge_.floor = merge_.floor;
  new_point_merge_.pixel_fraction = options_.merge_new_pixels;
  Triangulate(points, steiner.points, &stats);
  stats.seconds_triangulation = timer.Seconds();
  spdlog::info(
      "manifold: Delaunay of {} points + {} Steiner points ({} graded): {} cells in {:.2f} s",
      points.size(), steiner.points.size(), steiner.graded, stats.cells,
      stats.seconds_triangulation);

  timer.Restart();
  TraceRays(points, &stats);
  CountRaysBehind();
  if (options_.visibility == FreeSpaceRule::kCut) CutFreeSpace();
  stats.seconds_ray_tracing = timer.Seconds();
  // What the manifold needs of the points is in it now; growing is the build's peak of memory,
  // so the points with their cameras go before it.
  std::vector<RayPoint>().swap(points);
  ReleaseFreeMemory();
  spdlog::info("manifold: traced {} rays ({} cell steps) in {:.2f} s ({:.0f} rays/s)", stats.rays,
               stats.ray_cell_steps, stats.seconds_ray_tracing,
               stats.seconds_ray_tracing > 0 ? stats.rays / stats.seconds_ray_tracing : 0.0);

  timer.Restart();
  GrowInitial(&stats);
  stats.seconds_growing = timer.Seconds();
  spdlog::info(
      "manifold: grew O to {} of {} free cells ({} pockets joined, with {} pinching slivers) in "
      "{:.2f} s",
      stats.outside_cells, stats.free_cells, stats.pockets_joined, stats.slivers_joined,
      stats.seconds_growing);
  LogCameraStars(stats.camera_stars_completed);
  if (options_.validate_each_step) {
    const std::string problem = Validate(true);
    if (!problem.empty()) throw InternalError("manifold invalid after build: " + problem);
  }
  return stats;
}

void DelaunayManifold::Impl::CheckAndBound(const std::vector<RayPoint>& points, Eigen::Vector3d* lo,
                                           Eigen::Vector3d* hi) const {
  BoundPointsAndCameras(points, cameras_, lo, hi);
}

SteinerPoints DelaunayManifold::Impl::PlaceSteinerPoints(const std::vector<RayPoint>& points,
                                                         const Eigen::Vector3d& lo,
                                                         const Eigen::Vector3d& hi,
                                                         BuildStats* stats) {
  SteinerPoints made = ms::PlaceSteinerPoints(points, cameras_, lo, hi, options_);
  labels_.set_graded(SteinerCellsFree(options_));
  stats->steiner_points = static_cast<int64_t>(made.points.size());
  stats->graded_steiner_points = made.graded;
  box_min_ = Eigen::Vector3d::Constant(INFINITY);
  box_max_ = -box_min_;
  for (const Eigen::Vector3d& s : made.points) {
    box_min_ = box_min_.cwiseMin(s);
    box_max_ = box_max_.cwiseMax(s);
  }
  return made;
}

void DelaunayManifold::Impl::Triangulate(const std::vector<RayPoint>& points,
                                         const std::vector<Eigen::Vector3d>& steiner,
                                         BuildStats* stats) {
  // A near-duplicate joins the point it duplicates: never a vertex, its rays end there.
  const std::vector<int32_t> representative =
      NearDuplicateRepresentatives(points, cameras_, merge_);
  // Steiner points and input points together (CGAL sorts spatially).
  std::vector<std::pair<Point, VertexInfo>> vertices;
  vertices.reserve(steiner.size() + points.size());
  for (size_t k = 0; k < steiner.size(); ++k) {
    vertices.push_back({ToPoint(steiner[k]), {static_cast<int32_t>(-1 - k), 0, 0, 0, 0}});
  }
  for (size_t i = 0; i < points.size(); ++i) {
    if (representative[i] != static_cast<int32_t>(i)) continue;
    vertices.push_back({ToPoint(points[i].position), {static_cast<int32_t>(i), 0, 0, 0, 0}});
  }
  dt_.insert(vertices.begin(), vertices.end());
  positions_.reserve(points.size());
  vertex_of_point_.assign(points.size(), Vertex_handle());
  for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end(); ++v) {
    if (v->info().id >= 0) vertex_of_point_[v->info().id] = v;
  }
  int64_t near_duplicates = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const int32_t r = representative[i];
    if (r != static_cast<int32_t>(i)) {
      // Its rays run to the representative's vertex, so they are indexed by its position.
      positions_.push_back(points[r].position);
      vertex_of_point_[i] = vertex_of_point_[r];
      ++stats->merged_duplicates;
      ++near_duplicates;
      continue;
    }
    positions_.push_back(points[i].position);
    if (vertex_of_point_[i] == Vertex_handle()) {
      // Same position as another point: its rays end at that vertex.
      Locate_type type;
      int li, lj;
      const Cell_handle c = dt_.locate(ToPoint(points[i].position), type, li, lj);
      MS_CHECK(type == Delaunay::VERTEX) << "point " << i << " not found after insertion";
      vertex_of_point_[i] = c->vertex(li);
      ++stats->merged_duplicates;
    }
  }
  if (near_duplicates > 0) {
    spdlog::info(
        "manifold: merged {} near-duplicate points into others ({} of a pixel's footprint, "
        "floor {:.3g})",
        near_duplicates, merge_.pixel_fraction, merge_.floor);
  }
  for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
    for (int i = 0; i < 4; ++i) ++c->vertex(i)->info().cells;
  }
  stats->vertices = num_vertices();
  stats->cells = num_cells();
}

void DelaunayManifold::Impl::TraceRays(const std::vector<RayPoint>& points, BuildStats* stats) {
  std::vector<Eigen::Vector3d> centers;
  for (const ManifoldCamera& c : cameras_) centers.push_back(c.center);
  walker_.LocateCameras(centers);
  // From here on a point's cameras are its rays in the index.
  for (size_t i = 0; i < points.size(); ++i) {
    for (int32_t c : SortedCameras(points[i].cameras)) {
      ray_index_->Add(c, static_cast<int32_t>(i), positions_[i]);
    }
  }
  ray_index_->Flush();
  Progress progress("manifold: ray tracing", static_cast<int64_t>(ray_index_->size()));
  // Walked from the index, in its order, a chunk at a time (no list of every ray: 12 bytes a
  // ray), on all cores.
  ray_index_->ForEachChunkInDirectionOrder(
      ParallelWalks::kChunk, [&](const std::vector<RayRef>& chunk) {
        stats->ray_cell_steps +=
            walks_.Run(chunk.size(), [&](size_t i, auto& marks, WalkScratch& scratch, auto& count) {
              return walker_.WalkFromCameraWith(chunk[i].camera, vertex_of_point_[chunk[i].point],
                                                marks, scratch, count);
            });
        stats->rays += static_cast<int64_t>(chunk.size());
        progress.Update(stats->rays);
      });
}

DelaunayManifold::Impl::Cell_handle DelaunayManifold::Impl::CellBehindRay(
    const RayRef& ray, std::vector<Cell_handle>* star) const {
  const Vertex_handle v = vertex_of_point_[ray.point];
  star->clear();
  dt_.finite_incident_cells(v, std::back_inserter(*star));
  return manifold_detail::CellBehind(v, walker_.camera_point(ray.camera), *star);
}

void DelaunayManifold::Impl::CountRaysBehind() {
  if (options_.behind_ratio <= 0) return;
  std::vector<Cell_handle> star;
  ray_index_->ForEachInDirectionOrder([&](const RayRef& ray) {
    const Cell_handle c = CellBehindRay(ray, &star);
    if (c != Cell_handle()) labels_.CountBehind(c);
  });
}

void DelaunayManifold::Impl::CountRaysBehindAfterBatch(const InsertionBatch& batch) {
  if (options_.behind_ratio <= 0) return;
  std::vector<Cell_handle> star;
  ray_index_->ForEachInDirectionOrder([&](const RayRef& ray) {
    const bool new_ray = static_cast<size_t>(ray.id) >= batch.first_new_ray;
    if (!new_ray && vertex_of_point_[ray.point]->info().changed != batch.number) return;
    const Cell_handle c = CellBehindRay(ray, &star);
    if (c == Cell_handle()) return;
    if (new_ray || c->info().born >= batch.first_part) labels_.CountBehind(c);
  });
}

void DelaunayManifold::Impl::GrowInitial(BuildStats* stats) {
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    stats->free_cells += labels_.IsFree(c);
  }
  grow_shrink_.GrowFromHeaviest();
  const int64_t slivers_before = grow_shrink_.slivers_joined();
  stats->camera_stars_completed = FreeEnclosedCameras(nullptr);
  // Without the pinch joins: on sparse SfM points they take real matter into O, and the fins
  // they mend come from insertions (docs/design/accuracy.md, "Fins in front of the cameras").
  stats->pockets_joined = JoinFreePockets(RegrowSeeds::kBoundary, 0, /*pinch_rounds=*/0);
  stats->slivers_joined = grow_shrink_.slivers_joined() - slivers_before;
  stats->outside_cells = labels_.outside_count();
  stats->free_cells_left_inside = CountFreeCellsInside();
  const manifold_detail::Regularity::Counts& counts = regularity_.counts();
  stats->manifold_tests = counts.fast;
  stats->full_manifold_tests = counts.full;
  stats->link_steps = counts.link_steps;
}

// ---------------------------------------------------------------------------------------------
// Incremental insertion

InsertionStats DelaunayManifold::Impl::Insert(const std::vector<RayPoint>& points) {
  BeginInsert();
  InsertPart(points);
  return FinishInsert();
}

void DelaunayManifold::Impl::BeginInsert() {
  MS_CHECK(built_) << "Insert before Build";
  MS_CHECK(!open_batch_) << "BeginInsert with a batch open";
  // Cells created in a part carry its number; their ray counts are rebuilt ray by ray as the
  // parts go (EndPart) and at the end (shrinking and the discard rule do not depend on
  // weights, only growing does, once, in FinishInsert).
  open_batch_ = StartBatch();
  open_stats_ = InsertionStats();
}

void DelaunayManifold::Impl::InsertPart(const std::vector<RayPoint>& points) {
  MS_CHECK(open_batch_) << "InsertPart without BeginInsert";
  CheckNewPoints(points);
  Timer timer;
  InsertionStats& stats = open_stats_;
  InsertionBatch& batch = *open_batch_;
  stats.requested += static_cast<int64_t>(points.size());
  MS_CHECK(parts_ < CellInfo::kMaxPart) << "insertion parts past " << CellInfo::kMaxPart;
  batch.part = ++parts_;
  batch.marked_in.emplace_back();
  batch.first_new_id = static_cast<int32_t>(positions_.size());
  Progress progress("manifold: inserting points", static_cast<int64_t>(points.size()));
  for (size_t n = 0; n < points.size(); ++n) {
    progress.Update(static_cast<int64_t>(n));
    InsertOne(points[n], &batch, &stats);
  }
  EndPart(&batch, &stats);
  stats.seconds_insertion += timer.Seconds();
}

InsertionStats DelaunayManifold::Impl::FinishInsert() {
  MS_CHECK(open_batch_) << "FinishInsert without BeginInsert";
  InsertionBatch batch = std::move(*open_batch_);
  open_batch_.reset();
  InsertionStats stats = open_stats_;
  Timer timer;
  // What is left of the recount: the rays marked in the last kRecountLag parts, or every ray.
  if (batch.all_affected) {
    RewalkAll(&batch, &stats);
  } else {
    RewalkMarked(&batch, batch.part, &stats);
  }
  CountRaysBehindAfterBatch(batch);
  // The cut decides the batch's new cells too, and may change its verdict on older ones: O
  // then grows into what it frees (a cell in O stays there). Left to the threshold, new cells
  // beside cells the cut decided raise fins in front of cameras (docs/design/manifold.md, "The
  // free-space cut").
  if (options_.visibility == FreeSpaceRule::kCut) CutFreeSpace();
  stats.seconds_insertion += timer.Seconds();

  timer.Restart();
  Regrow(batch, &stats);
  LogCameraStars(stats.camera_stars_completed);
  stats.outside_cells = labels_.outside_count();
  stats.seconds_growing = timer.Seconds();
  spdlog::info(
      "manifold: {} new points: {} inserted, {} discarded (conflict {}, duplicate {}, outside "
      "{}), {} cells shrunk, {} rays re-walked, {} pockets joined (with {} pinching slivers); "
      "{:.2f} s inserting, {:.2f} s regrowing",
      stats.requested, stats.inserted,
      stats.discarded_conflict + stats.discarded_duplicate + stats.discarded_outside,
      stats.discarded_conflict, stats.discarded_duplicate, stats.discarded_outside,
      stats.shrunk_cells, stats.rewalked_rays, stats.pockets_joined, stats.slivers_joined,
      stats.seconds_insertion, stats.seconds_growing);
  if (options_.validate_each_step) {
    const std::string problem = Validate(true);
    if (!problem.empty()) throw InternalError("manifold invalid after insertion: " + problem);
  }
  return stats;
}

void DelaunayManifold::Impl::CheckNewPoints(const std::vector<RayPoint>& points) const {
  for (size_t n = 0; n < points.size(); ++n) {
    if (!points[n].position.allFinite()) {
      throw InputError("new point " + std::to_string(n) + ": position is not finite");
    }
    for (int32_t c : points[n].cameras) {
      if (c < 0 || c >= static_cast<int32_t>(cameras_.size())) {
        throw InputError("new point " + std::to_string(n) + ": camera " + std::to_string(c) +
                         " out of range");
      }
    }
  }
}

DelaunayManifold::Impl::InsertionBatch DelaunayManifold::Impl::StartBatch() {
  InsertionBatch batch;
  batch.number = ++batch_;
  batch.first_part = parts_ + 1;
  batch.part = parts_;
  batch.first_new_id = static_cast<int32_t>(positions_.size());
  batch.first_new_ray = ray_index_->size();
  batch.rays.Reset(ray_index_->size(), parts_);
  batch.box_slack = 1e-9 * (box_max_ - box_min_).norm();
  return batch;
}

void DelaunayManifold::Impl::InsertOne(const RayPoint& point, InsertionBatch* batch,
                                       InsertionStats* stats) {
  const Point p = ToPoint(point.position);
  Cell_handle located;
  if (!FindConflictRegion(point, p, batch, &located, stats)) return;
  if (!ShrinkAround(*batch, stats)) {
    // Discarded (the paper's rule); the cells shrunk for it stay out of O until regrowing.
    ++stats->discarded_conflict;
    batch->hint = located;
    return;
  }
  MarkRaysNear(batch, stats);
  InsertPoint(p, point, batch, stats);
}

bool DelaunayManifold::Impl::FindConflictRegion(const RayPoint& point, const Point& p,
                                                InsertionBatch* batch, Cell_handle* located,
                                                InsertionStats* stats) {
  const Eigen::Vector3d& position = point.position;
  if (!InSteinerBox(position)) {
    ++stats->discarded_outside;
    return false;
  }
  Locate_type type;
  int li, lj;
  *located = dt_.locate(p, type, li, lj, batch->hint);
  if (type == Delaunay::VERTEX) {
    ++stats->discarded_duplicate;
    GainCameras((*located)->vertex(li), point.cameras, batch);
    return false;
  }
  if (type == Delaunay::OUTSIDE_CONVEX_HULL || type == Delaunay::OUTSIDE_AFFINE_HULL) {
    ++stats->discarded_outside;
    return false;
  }
  // Nearer an existing vertex than the merge tolerance: that vertex gains the point's cameras
  // (its visibility is kept, not its position).
  const Vertex_handle nearest = dt_.nearest_vertex(p, *located);
  if ((ToEigen(nearest->point()) - position).norm() <
      DuplicateDistance(position, point.cameras, cameras_, new_point_merge_)) {
    ++stats->discarded_duplicate;
    GainCameras(nearest, point.cameras, batch);
    batch->hint = *located;
    return false;
  }
  batch->conflicts.clear();
  batch->boundary.clear();
  dt_.find_conflicts(p, *located, std::back_inserter(batch->boundary),
                     std::back_inserter(batch->conflicts));
  if (std::any_of(batch->conflicts.begin(), batch->conflicts.end(),
                  [&](const Cell_handle& c) { return dt_.is_infinite(c); })) {
    ++stats->discarded_outside;
    return false;
  }
  return true;
}

bool DelaunayManifold::Impl::ShrinkAround(const InsertionBatch& batch, InsertionStats* stats) {
  const uint32_t stamp = walker_.NextStamp();
  return grow_shrink_.ShrinkAround(batch.conflicts, stamp, batch.number, &stats->shrunk_cells);
}

void DelaunayManifold::Impl::MarkRaysNear(InsertionBatch* batch, InsertionStats* stats) {
  // Old rays that may cross the hole (conservative box query), for the recount.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const Cell_handle& c : batch->conflicts) {
    for (int i = 0; i < 4; ++i) {
      const Point& q = c->vertex(i)->point();
      const Eigen::Vector3d x(q.x(), q.y(), q.z());
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
  }
  // A candidate costs about what 1/20 of a whole re-walk does: past 20 candidates per ray in
  // the batch (large conflict regions: the box-only Steiner grid's long cells) every ray is
  // walked once, at the end of the batch.
  if (!batch->all_affected &&
      stats->candidate_rays > 20 * static_cast<int64_t>(ray_index_->size())) {
    batch->all_affected = true;
  }
  std::vector<RayRef>& candidates = batch->candidates;
  candidates.clear();
  if (!batch->all_affected) ray_index_->Query(lo, hi, &candidates);
  stats->candidate_rays += static_cast<int64_t>(candidates.size());
  const Eigen::Vector3d slack = Eigen::Vector3d::Constant(batch->box_slack);
  for (const RayRef& ray : candidates) {
    double entry;
    if (SegmentMeetsBox(cameras_[ray.camera].center, positions_[ray.point], lo - slack, hi + slack,
                        &entry)) {
      BatchRays::State& state = batch->rays.Touch(ray.id);
      // Rounded down (float), so the walk starts no later than the box.
      state.reach = std::min(state.reach, static_cast<float>(entry) - 1e-6f);
      if (state.marked != batch->part) {
        state.marked = batch->part;
        batch->marked_in.back().push_back(ray);
      }
    }
  }
}

void DelaunayManifold::Impl::InsertPoint(const Point& p, const RayPoint& point,
                                         InsertionBatch* batch, InsertionStats* stats) {
  for (const Cell_handle& c : batch->conflicts) {
    // Destroyed below.
    if (c->info().has_camera) walker_.ForgetStartsIn(c);
    labels_.ForgetCounts(c);
    for (int i = 0; i < 4; ++i) --c->vertex(i)->info().cells;
  }
  const Vertex_handle v =
      dt_.insert_in_hole(p, batch->conflicts.begin(), batch->conflicts.end(),
                         batch->boundary.front().first, batch->boundary.front().second);
  v->info() = VertexInfo{static_cast<int32_t>(positions_.size()), 0, 0, 0, batch->number};
  std::vector<Cell_handle>& around = batch->around;
  around.clear();
  dt_.incident_cells(v, std::back_inserter(around));
  for (const Cell_handle& c : around) {
    c->info() = CellInfo{};
    c->info().born = batch->part;
    for (int i = 0; i < 4; ++i) {
      ++c->vertex(i)->info().cells;
      c->vertex(i)->info().changed = batch->number;
    }
  }
  positions_.push_back(point.position);
  batch->part_cameras.push_back(SortedCameras(point.cameras));
  vertex_of_point_.push_back(v);
  ++stats->inserted;
  batch->hint = v->cell();
}

// The end of a part: the rays no part has marked for kRecountLag parts are walked (the holes
// have moved on), then the part's new rays are traced and join the index.
void DelaunayManifold::Impl::EndPart(InsertionBatch* batch, InsertionStats* stats) {
  if (!batch->all_affected && batch->part >= batch->first_part + kRecountLag) {
    RewalkMarked(batch, batch->part - kRecountLag, stats);
  }
  TraceNewRays(batch, stats);
  batch->rays.AddTraced(ray_index_->size(), batch->part);
}

// Walks the pending rays whose last mark came from a part <= last_marked_by, camera by camera
// (consecutive walks share cells in cache).
void DelaunayManifold::Impl::RewalkMarked(InsertionBatch* batch, uint32_t last_marked_by,
                                          InsertionStats* stats) {
  std::vector<RayRef> due;
  for (uint32_t q = batch->first_part; q <= last_marked_by; ++q) {
    std::vector<RayRef>& bucket = batch->marked_in[q - batch->first_part];
    for (const RayRef& ray : bucket) {
      // Pending, and in the bucket of its last mark (not marked again since).
      const BatchRays::State state = batch->rays.Get(ray.id);
      if (state.marked == q && state.reach <= 1.0f) due.push_back(ray);
    }
    std::vector<RayRef>().swap(bucket);
  }
  std::sort(due.begin(), due.end());
  std::vector<float> reach;
  reach.reserve(due.size());
  for (const RayRef& ray : due) reach.push_back(batch->rays.Get(ray.id).reach);
  Rewalk(*batch, due, reach, stats);
  for (const RayRef& ray : due) {
    BatchRays::State& state = batch->rays.Touch(ray.id);
    state.counted = batch->part;
    state.reach = 2.0f;
  }
}

// Every ray from its camera on (a batch whose holes meet most rays), a chunk at a time.
void DelaunayManifold::Impl::RewalkAll(InsertionBatch* batch, InsertionStats* stats) {
  ray_index_->ForEachChunkInDirectionOrder(
      ParallelWalks::kChunk,
      [&](const std::vector<RayRef>& chunk) { Rewalk(*batch, chunk, /*reach=*/{}, stats); });
  for (std::vector<RayRef>& bucket : batch->marked_in) std::vector<RayRef>().swap(bucket);
  batch->rays.Reset(ray_index_->size(), batch->part);  // every ray is counted now
}

void DelaunayManifold::Impl::Rewalk(const InsertionBatch& batch, const std::vector<RayRef>& rays,
                                    const std::vector<float>& reach, InsertionStats* stats) {
  walker_.LocateStarts();  // a ray whose walk back is degenerate walks from its camera
  stats->rewalk_steps +=
      walks_.Run(rays.size(), [&](size_t i, auto& marks, WalkScratch& scratch, auto& count) {
        return RewalkRay(batch, rays[i], reach.empty() ? 0.0f : reach[i], marks, scratch, count);
      });
  stats->rewalked_rays += static_cast<int64_t>(rays.size());
}

template <typename Marks, typename Record>
int64_t DelaunayManifold::Impl::RewalkRay(const InsertionBatch& batch, const RayRef& ray,
                                          float reach, Marks& marks, WalkScratch& scratch,
                                          Record& record) const {
  const uint32_t after = batch.rays.Get(ray.id).counted, upto = batch.part;
  const auto is_new = [&](const Cell_handle& c) {
    return c->info().born > after && c->info().born <= upto;
  };
  const auto record_new_cells = [&](const Cell_handle& c, unsigned mask) {
    if (is_new(c)) record(c, mask);
  };
  const Vertex_handle target = vertex_of_point_[ray.point];
  // Only the part of the ray from its first hole box on can cross a new cell: walk that part
  // backwards from the point; where that is degenerate, the whole ray forwards.
  int64_t steps = 0;
  if (reach <= 0 || !walker_.WalkBackWith(walker_.camera_point(ray.camera), target, reach, is_new,
                                          marks, scratch, record_new_cells, &steps)) {
    steps += walker_.WalkFromCameraWith(ray.camera, target, marks, scratch, record_new_cells);
  }
  return steps;
}

// The cameras of a duplicate that `vertex` does not have yet, for TraceNewRays (Steiner vertices
// gain none: they are no observation).
void DelaunayManifold::Impl::GainCameras(const Vertex_handle& vertex,
                                         const std::vector<int32_t>& cameras,
                                         InsertionBatch* batch) {
  const int32_t id = vertex->info().id;
  if (id < 0) return;
  // A point of this part has its cameras in the batch until its rays join the index.
  const std::vector<int32_t>* in_part =
      id >= batch->first_new_id ? &batch->part_cameras[id - batch->first_new_id] : nullptr;
  for (int32_t c : cameras) {
    const bool has = in_part != nullptr ? std::binary_search(in_part->begin(), in_part->end(), c)
                                        : ray_index_->Contains(c, id, positions_[id]);
    if (!has) batch->gained_rays.emplace_back(id, c);
  }
}

// The new points' rays, and the rays existing vertices gained from duplicates, are walked and
// counted everywhere, then join the index.
void DelaunayManifold::Impl::TraceNewRays(InsertionBatch* batch, InsertionStats* stats) {
  // Several duplicates of one vertex may bring the same camera: each ray once.
  std::vector<std::pair<int32_t, int32_t>>& gained = batch->gained_rays;
  std::sort(gained.begin(), gained.end());
  gained.erase(std::unique(gained.begin(), gained.end()), gained.end());
  std::vector<RayRef> rays;  // to walk and file, in this order
  for (const auto& [id, c] : gained) {
    vertex_of_point_[id]->info().changed = batch->number;  // growing looks at its cells again
    ++stats->gained_rays;
    // A point new in this part has its rays, the gained one included, traced below.
    if (id >= batch->first_new_id) {
      std::vector<int32_t>& cams = batch->part_cameras[id - batch->first_new_id];
      cams.insert(std::upper_bound(cams.begin(), cams.end(), c), c);
      continue;
    }
    rays.push_back({c, id});
  }
  for (int32_t id = batch->first_new_id; id < static_cast<int32_t>(positions_.size()); ++id) {
    for (int32_t c : batch->part_cameras[id - batch->first_new_id]) rays.push_back({c, id});
  }
  walker_.LocateStarts();
  walks_.Run(rays.size(), [&](size_t i, auto& marks, WalkScratch& scratch, auto& count) {
    return walker_.WalkFromCameraWith(rays[i].camera, vertex_of_point_[rays[i].point], marks,
                                      scratch, count);
  });
  for (const RayRef& ray : rays) ray_index_->Add(ray.camera, ray.point, positions_[ray.point]);
  stats->new_rays += static_cast<int64_t>(rays.size());
  gained.clear();
  batch->part_cameras.clear();
  ray_index_->Flush();
}

// From the cells on the boundary of O that the batch may have changed: a cell none of whose
// vertices touches a new or shrunk cell has the weight and neighbourhood it had when the last
// growing refused it.
void DelaunayManifold::Impl::Regrow(const InsertionBatch& batch, InsertionStats* stats) {
  if (stats->inserted == 0 && stats->shrunk_cells == 0 && stats->gained_rays == 0) return;
  // From every free cell next to O (the default), Grow leaves them all in `boundary`, which the
  // camera stars and the pocket joins then keep up to date.
  GrowShrink::Refusals boundary(GrowShrink::Refusals::Kind::kRequeued);
  grow_shrink_.Grow(grow_shrink_.BoundarySeeds(options_.regrow_seeds, batch.number), nullptr,
                    &boundary);
  boundary.Index();
  bool whole_boundary = options_.regrow_seeds == RegrowSeeds::kBoundary;
  if (labels_.outside_count() == 0) {
    grow_shrink_.GrowFromHeaviest();
    whole_boundary = false;
  }
  const int64_t slivers_before = grow_shrink_.slivers_joined();
  stats->camera_stars_completed = FreeEnclosedCameras(whole_boundary ? &boundary : nullptr);
  stats->pockets_joined =
      JoinFreePockets(options_.regrow_seeds, batch.number, options_.pocket_pinch_rounds,
                      whole_boundary ? &boundary : nullptr);
  stats->slivers_joined = grow_shrink_.slivers_joined() - slivers_before;
}

void DelaunayManifold::Impl::LogCameraStars(int64_t completed) const {
  if (completed == 0) return;
  spdlog::info(
      "manifold: growing had left cameras in the matter; {} vertex star(s) completed to bring "
      "them back into free space",
      completed);
}

int64_t DelaunayManifold::Impl::FreeEnclosedCameras(GrowShrink::Refusals* boundary) {
  return grow_shrink_.FreeEnclosedCameras(
      [this] { return CamerasInMatter(); },
      [this](int32_t camera) { return walker_.StartCandidates(walker_.StartOf(camera)); },
      [this] { return walker_.NextStamp(); }, boundary);
}

int64_t DelaunayManifold::Impl::JoinFreePockets(RegrowSeeds which, uint32_t changed_in,
                                                int pinch_rounds,
                                                manifold_detail::GrowShrink::Refusals* boundary) {
  return grow_shrink_.JoinFreePockets(which, changed_in, pinch_rounds, boundary,
                                      [this] { return walker_.NextStamp(); });
}

// ---------------------------------------------------------------------------------------------
// Surface extraction

Mesh DelaunayManifold::Impl::ExtractSurface(SurfaceInfo* info) const {
  // The surface's vertices are those with a face between O and the rest (the count SetOutside
  // keeps), numbered by id; ids run from the last Steiner point's (negative) to the last point's.
  std::vector<std::pair<int32_t, Vertex_handle>> used;
  for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end(); ++v) {
    if (v->info().surface_faces > 0) used.emplace_back(v->info().id, v);
  }
  std::sort(used.begin(), used.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::array<int32_t, 3>> faces;  // by vertex id
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    if (!c->info().outside) continue;
    for (int i = 0; i < 4; ++i) {
      // Normals towards O (free space).
      if (!labels_.InO(c->neighbor(i))) faces.push_back(FaceIntoCell(c, i));
    }
  }
  // A face's vertex missing from `used` is a vertex whose surface-face count is wrong.
  Mesh mesh = MeshByIds(used, std::move(faces));
  if (info != nullptr) {
    info->vertex_ids.clear();
    for (const auto& [id, v] : used) info->vertex_ids.push_back(id);
    info->steiner_vertices = std::count_if(info->vertex_ids.begin(), info->vertex_ids.end(),
                                           [](int32_t id) { return id < 0; });
  }
  return mesh;
}

Mesh DelaunayManifold::Impl::ExtractFreeSpaceBoundary() const {
  std::vector<std::pair<int32_t, Vertex_handle>> used;  // the faces' vertices, repeated
  std::vector<std::array<int32_t, 3>> faces;            // by vertex id
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    if (!labels_.IsFree(c)) continue;
    for (int i = 0; i < 4; ++i) {
      if (labels_.IsFree(c->neighbor(i))) continue;
      faces.push_back(FaceIntoCell(c, i));  // normal into the free cell c
      for (int j = 0; j < 4; ++j) {
        if (j != i) used.emplace_back(c->vertex(j)->info().id, c->vertex(j));
      }
    }
  }
  std::sort(used.begin(), used.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  used.erase(std::unique(used.begin(), used.end(),
                         [](const auto& a, const auto& b) { return a.first == b.first; }),
             used.end());
  return MeshByIds(used, std::move(faces));
}

// ---------------------------------------------------------------------------------------------
// Public interface

Mesh SurfaceWithoutSteinerFaces(const Mesh& mesh, const SurfaceInfo& info) {
  MS_CHECK(info.vertex_ids.size() == mesh.vertices.size()) << "SurfaceInfo of another mesh";
  return FacesWithoutFlaggedVertices(mesh, SteinerFlags(info));
}

std::vector<uint8_t> SteinerFlags(const SurfaceInfo& info) {
  std::vector<uint8_t> steiner(info.vertex_ids.size());
  for (size_t v = 0; v < steiner.size(); ++v) steiner[v] = info.vertex_ids[v] < 0;
  return steiner;
}

DelaunayManifold::DelaunayManifold(std::vector<ManifoldCamera> cameras,
                                   const ManifoldOptions& options)
    : impl_(std::make_unique<Impl>(std::move(cameras), options)) {
  if (options.insertion == InsertionMode::kRebuild) rebuild_ = std::make_unique<Rebuild>();
}
DelaunayManifold::~DelaunayManifold() = default;
BuildStats DelaunayManifold::Build(std::vector<RayPoint> points) {
  if (!rebuild_) return impl_->Build(std::move(points));
  rebuild_->points = points;
  const BuildStats stats = impl_->Build(std::move(points));
  rebuild_->merged_duplicates = stats.merged_duplicates;
  rebuild_->box_min = impl_->box_min_;
  rebuild_->box_max = impl_->box_max_;
  return stats;
}
InsertionStats DelaunayManifold::Insert(const std::vector<RayPoint>& points) {
  BeginInsert();
  InsertPart(points);
  return FinishInsert();
}
void DelaunayManifold::BeginInsert() {
  if (rebuild_) return RebuildBegin();
  impl_->BeginInsert();
}
void DelaunayManifold::InsertPart(const std::vector<RayPoint>& points) {
  if (rebuild_) return RebuildAppend(points);
  impl_->InsertPart(points);
}
InsertionStats DelaunayManifold::FinishInsert() {
  return rebuild_ ? RebuildFinish() : impl_->FinishInsert();
}

void DelaunayManifold::RebuildBegin() {
  MS_CHECK(impl_->built()) << "Insert before Build";
  MS_CHECK(!rebuild_->open) << "BeginInsert with a batch open";
  rebuild_->open = true;
  rebuild_->stats = InsertionStats();
  rebuild_->batch_begin = rebuild_->points.size();
}

void DelaunayManifold::RebuildAppend(const std::vector<RayPoint>& points) {
  MS_CHECK(rebuild_->open) << "InsertPart without BeginInsert";
  impl_->CheckNewPoints(points);
  InsertionStats& stats = rebuild_->stats;
  stats.requested += static_cast<int64_t>(points.size());
  for (const RayPoint& point : points) {
    if (StrictlyInsideBox(point.position, rebuild_->box_min, rebuild_->box_max)) {
      rebuild_->points.push_back(point);
    } else {
      ++stats.discarded_outside;
    }
  }
}

InsertionStats DelaunayManifold::RebuildFinish() {
  MS_CHECK(rebuild_->open) << "FinishInsert without BeginInsert";
  rebuild_->open = false;
  InsertionStats stats = rebuild_->stats;
  // Build lets go of its points; the copy is what the next batch rebuilds from.
  auto fresh = std::make_unique<Impl>(impl_->cameras(), impl_->options());
  fresh->set_walk_threads(impl_->walk_threads());
  const BuildStats built = fresh->Build(rebuild_->points);
  impl_ = std::move(fresh);
  const int64_t appended = static_cast<int64_t>(rebuild_->points.size() - rebuild_->batch_begin);
  // A near-duplicate joins the point it duplicates, as in Build: its cameras are gained.
  stats.discarded_duplicate =
      std::max<int64_t>(0, built.merged_duplicates - rebuild_->merged_duplicates);
  stats.inserted = appended - stats.discarded_duplicate;
  rebuild_->merged_duplicates = built.merged_duplicates;
  stats.new_rays = built.rays;
  stats.outside_cells = built.outside_cells;
  stats.camera_stars_completed = built.camera_stars_completed;
  stats.pockets_joined = built.pockets_joined;
  stats.slivers_joined = built.slivers_joined;
  stats.seconds_insertion = built.seconds_triangulation + built.seconds_ray_tracing;
  stats.seconds_growing = built.seconds_growing;
  spdlog::info("manifold: rebuilt from {} points ({} new, {} merged into others, {} outside)",
               rebuild_->points.size(), appended, stats.discarded_duplicate,
               stats.discarded_outside);
  return stats;
}

Mesh DelaunayManifold::ExtractSurface(SurfaceInfo* info) const {
  return impl_->ExtractSurface(info);
}
Mesh DelaunayManifold::ExtractFreeSpaceBoundary() const {
  return impl_->ExtractFreeSpaceBoundary();
}
std::string DelaunayManifold::Validate(bool check_weights) const {
  return impl_->Validate(check_weights);
}
void DelaunayManifold::set_walk_threads(int threads) { impl_->set_walk_threads(threads); }
std::vector<RayPoint> DelaunayManifold::Points() const {
  if (rebuild_) return rebuild_->points;
  return impl_->Points();
}
int64_t DelaunayManifold::num_points() const { return impl_->num_points(); }
int64_t DelaunayManifold::num_vertices() const { return impl_->num_vertices(); }
int64_t DelaunayManifold::num_cells() const { return impl_->num_cells(); }
int64_t DelaunayManifold::num_outside_cells() const { return impl_->num_outside_cells(); }
int64_t DelaunayManifold::num_joinable_cells() const { return impl_->CountJoinableCells(); }
int64_t DelaunayManifold::num_free_cells_inside() const { return impl_->CountFreeCellsInside(); }
std::vector<int32_t> DelaunayManifold::CamerasInMatter() { return impl_->CamerasInMatter(); }
size_t DelaunayManifold::MemoryBytes() const {
  size_t bytes = impl_->MemoryBytes();
  if (rebuild_) {
    for (const RayPoint& p : rebuild_->points) {
      bytes += sizeof(RayPoint) + p.cameras.capacity() * sizeof(int32_t);
    }
  }
  return bytes;
}

}  // namespace ms
