#include "manifold/tile_manifold.h"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <limits>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "base/error.h"
#include "manifold/cell_labels.h"
#include "manifold/grow_shrink.h"
#include "manifold/ray_walker.h"
#include "manifold/rays_through_box.h"
#include "manifold/regularity.h"
#include "manifold/triangulation.h"

namespace ms {

using manifold_detail::Cell_handle;
using manifold_detail::Delaunay;
using manifold_detail::Vertex_handle;

namespace {

struct CellHash {
  size_t operator()(const TileManifold::Cell& k) const {
    uint64_t h = 1469598103934665603ull;
    for (int32_t v : k) h = (h ^ static_cast<uint32_t>(v)) * 1099511628211ull;
    return h;
  }
};

}  // namespace

class TileManifold::Impl {
 public:
  Impl(const std::vector<Eigen::Vector3d>& points, const std::vector<int32_t>& held,
       const std::function<bool(int32_t)>& owns, int32_t first_steiner, bool graded,
       const std::vector<Eigen::Vector3d>& cameras, const std::vector<ViewingRay>& rays,
       const ManifoldOptions& options, CellRayCountStats* ray_stats)
      : first_steiner_(first_steiner),
        owns_(owns),
        options_(options),
        labels_(dt_, options_),
        regularity_(dt_),
        grow_(dt_, options_, labels_, regularity_),
        walker_(dt_, cameras.size()),
        num_cameras_(static_cast<int32_t>(cameras.size())) {
    Triangulate(points, held);
    manifold_detail::LocateCamerasInside(cameras, &walker_);
    labels_.set_graded(graded);
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
      for (int i = 0; i < 4; ++i) ++c->vertex(i)->info().cells;
    }
    MarkFlippableCells();
    CountRays(points, cameras, rays, ray_stats);
  }

  std::optional<Seed> HeaviestFreeCell() const {
    std::optional<Seed> best;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (!labels_.FreeOutsideO(c)) continue;  // frozen cells are never free
      bool touches = false;
      for (int i = 0; i < 4; ++i) touches |= c->vertex(i)->info().outside_cells > 0;
      if (touches) continue;
      const Seed seed{labels_.Weight(c), KeyOf(c)};
      if (!owns_(seed.cell[0])) continue;  // another tile's to propose
      if (!best || seed.weight > best->weight ||
          (seed.weight == best->weight && seed.cell < best->cell)) {
        best = seed;
      }
    }
    return best;
  }

  std::vector<Cell> Grow(const std::optional<Cell>& seed, double min_weight) {
    std::vector<Cell_handle> seeds = grow_.BoundarySeeds(RegrowSeeds::kBoundary, 0);
    if (seed) {
      const Cell_handle c = FindOwned(*seed);
      if (c == Cell_handle()) throw InternalError("tile: a seed cell the tile does not own");
      seeds.push_back(c);
    }
    std::vector<Cell_handle> added;
    grow_.Grow(seeds, &added, nullptr, min_weight);
    std::vector<Cell> keys;
    keys.reserve(added.size());
    for (const Cell_handle& c : added) keys.push_back(KeyOf(c));
    return keys;
  }

  std::vector<Cell> FreeEnclosedCameras() {
    const std::vector<Cell> before = FlippableInO();
    // The cameras this tile answers for: a start cell it may flip, and none in O.
    const auto in_matter = [this] {
      std::vector<int32_t> enclosed;
      for (int32_t camera = 0; camera < num_cameras_; ++camera) {
        const std::vector<Cell_handle> cells = walker_.StartCandidates(walker_.StartOf(camera));
        const bool here = std::any_of(cells.begin(), cells.end(), [this](const Cell_handle& c) {
          return !dt_.is_infinite(c) && !c->info().frozen;
        });
        const bool free = std::any_of(cells.begin(), cells.end(),
                                      [this](const Cell_handle& c) { return labels_.InO(c); });
        if (here && !free) enclosed.push_back(camera);
      }
      return enclosed;
    };
    grow_.FreeEnclosedCameras(
        in_matter,
        [this](int32_t camera) { return walker_.StartCandidates(walker_.StartOf(camera)); },
        [this] { return walker_.NextStamp(); }, nullptr);
    return AddedSince(before);
  }

  std::vector<Cell> JoinPockets() {
    const std::vector<Cell> before = FlippableInO();
    grow_.JoinFreePockets(RegrowSeeds::kBoundary, 0, /*pinch_rounds=*/0, nullptr,
                          [this] { return walker_.NextStamp(); });
    return AddedSince(before);
  }

  int64_t SetLabels(const std::vector<Cell>& cells, bool outside) {
    int64_t changed = 0;
    for (const Cell& key : cells) {
      const auto it = read_cells_.find(key);
      if (it == read_cells_.end() || it->second->info().outside == outside) continue;
      labels_.SetOutside(it->second, outside);
      ++changed;
    }
    return changed;
  }

  std::vector<CellRayCount> OwnedCounts() const {
    std::vector<CellRayCount> counts;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      CellRayCount n;
      n.ids = KeyOf(c);
      if (!owns_(n.ids[0])) continue;
      n.crossings = c->info().crossings;
      for (int i = 0; i < 4; ++i) {
        // Face i is opposite vertex i: its place among the ascending ids.
        const int32_t opposite = TileId(c->vertex(i)->info().id);
        n.spread[std::find(n.ids.begin(), n.ids.end(), opposite) - n.ids.begin()] =
            labels_.Spread(c, i);
      }
      counts.push_back(n);
    }
    std::sort(counts.begin(), counts.end(),
              [](const CellRayCount& a, const CellRayCount& b) { return a.ids < b.ids; });
    return counts;
  }

  std::vector<Cell> OutsideCells() const {
    std::vector<Cell> cells;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (c->info().outside && owns_(KeyOf(c)[0])) cells.push_back(KeyOf(c));
    }
    std::sort(cells.begin(), cells.end());
    return cells;
  }

  std::vector<Face> SurfaceFaces() const {
    std::vector<Face> faces;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (!c->info().outside || !owns_(KeyOf(c)[0])) continue;
      for (int i = 0; i < 4; ++i) {
        if (labels_.InO(c->neighbor(i))) continue;
        Face face;  // the order that makes the normal point into c
        for (int j = 0; j < 3; ++j) {
          face[j] = TileId(c->vertex(Delaunay::vertex_triple_index(i, j))->info().id);
        }
        std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
        faces.push_back(face);
      }
    }
    return faces;
  }

 private:
  // Steiner points carry negative ids in the triangulation (-1 - k for the k-th), as in
  // DelaunayManifold, where the graded rule reads them.
  int32_t VertexId(int32_t id) const {
    return id < first_steiner_ ? id : -1 - (id - first_steiner_);
  }
  int32_t TileId(int32_t vertex_id) const {
    return vertex_id >= 0 ? vertex_id : first_steiner_ + (-1 - vertex_id);
  }
  Cell KeyOf(const Cell_handle& c) const {
    Cell key;
    for (int i = 0; i < 4; ++i) key[i] = TileId(c->vertex(i)->info().id);
    std::sort(key.begin(), key.end());
    return key;
  }
  // The cells in O that the tile may flip, ascending.
  std::vector<Cell> FlippableInO() const {
    std::vector<Cell> cells;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (!c->info().frozen && c->info().outside) cells.push_back(KeyOf(c));
    }
    std::sort(cells.begin(), cells.end());
    return cells;
  }
  // The cells the tile may flip that are in O now and were not in `before` (FlippableInO).
  std::vector<Cell> AddedSince(const std::vector<Cell>& before) const {
    std::vector<Cell> added;
    const std::vector<Cell> after = FlippableInO();
    std::set_difference(after.begin(), after.end(), before.begin(), before.end(),
                        std::back_inserter(added));
    return added;
  }
  Cell_handle FindOwned(const Cell& key) const {
    const auto it = read_cells_.find(key);
    return it != read_cells_.end() && owns_(key[0]) ? it->second : Cell_handle();
  }
  // Counts the rays on the cells it reads (cell_ray_counts.h): a ray that misses the box around
  // them crosses none. Walks count on every cell they cross, but only those cells' counts are
  // read: growing weighs the cells it may flip and their neighbours, all among them.
  void CountRays(const std::vector<Eigen::Vector3d>& points,
                 const std::vector<Eigen::Vector3d>& cameras, const std::vector<ViewingRay>& rays,
                 CellRayCountStats* stats) {
    const auto start = std::chrono::steady_clock::now();
    CellRayCountStats local;
    if (stats == nullptr) stats = &local;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (const auto& [key, c] : read_cells_) {
      for (int i = 0; i < 4; ++i) {
        const Eigen::Vector3d p = manifold_detail::ToEigen(c->vertex(i)->point());
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
    if (read_cells_.empty()) return;
    manifold_detail::WalkRaysMeetingBox(points, cameras, rays, lo, hi, &walker_, stats,
                                        [this](const Cell_handle& c, unsigned camera_side) {
                                          labels_.CountCrossing(c, camera_side);
                                        });
    stats->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  // The tile flips its own cells, and other tiles' cells whose four vertices are vertices of
  // its own cells: their stars are exact here, so their flips are tested as the whole
  // triangulation would test them (a pocket of free space across a seam joins whole). Every
  // other cell is frozen. The cells around the vertices of its own cells are those whose
  // labels it reads (read_cells_).
  void MarkFlippableCells() {
    std::unordered_set<const void*> near_own;  // vertices of owned cells
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (!owns_(KeyOf(c)[0])) continue;
      for (int i = 0; i < 4; ++i) near_own.insert(&*c->vertex(i));
    }
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      int near = 0;
      for (int i = 0; i < 4; ++i) near += near_own.count(&*c->vertex(i)) > 0 ? 1 : 0;
      c->info().frozen = near < 4;
      if (near > 0) read_cells_.emplace(KeyOf(c), c);
    }
  }
  void Triangulate(const std::vector<Eigen::Vector3d>& points, const std::vector<int32_t>& held) {
    std::vector<std::pair<manifold_detail::Point, manifold_detail::VertexInfo>> input;
    input.reserve(held.size());
    for (int32_t id : held) {
      if (id < 0 || static_cast<size_t>(id) >= points.size()) {
        throw InputError("tile: held point id " + std::to_string(id) + " is out of range");
      }
      manifold_detail::VertexInfo info;
      info.id = VertexId(id);
      input.emplace_back(manifold_detail::ToPoint(points[id]), info);
    }
    dt_.insert(input.begin(), input.end());
    if (dt_.number_of_vertices() != held.size()) {
      throw InputError("tile: the held points repeat a position");
    }
    if (dt_.dimension() < 3) throw InputError("tile: the held points span no volume");
  }

  const int32_t first_steiner_;
  const std::function<bool(int32_t)> owns_;
  const ManifoldOptions options_;
  Delaunay dt_;
  manifold_detail::CellLabels labels_;
  manifold_detail::Regularity regularity_;
  manifold_detail::GrowShrink grow_;
  manifold_detail::RayWalker walker_;  // the cameras' start cells and the visit stamps
  const int32_t num_cameras_;
  std::unordered_map<Cell, Cell_handle, CellHash> read_cells_;
};

TileManifold::TileManifold(const std::vector<Eigen::Vector3d>& points,
                           const std::vector<int32_t>& held,
                           const std::function<bool(int32_t)>& owns, int32_t first_steiner,
                           bool graded, const std::vector<Eigen::Vector3d>& cameras,
                           const std::vector<ViewingRay>& rays, const ManifoldOptions& options,
                           CellRayCountStats* ray_stats)
    : impl_(std::make_unique<Impl>(points, held, owns, first_steiner, graded, cameras, rays,
                                   options, ray_stats)) {}
TileManifold::~TileManifold() = default;
TileManifold::TileManifold(TileManifold&&) noexcept = default;
TileManifold& TileManifold::operator=(TileManifold&&) noexcept = default;

std::optional<TileManifold::Seed> TileManifold::HeaviestFreeCell() const {
  return impl_->HeaviestFreeCell();
}
std::vector<TileManifold::Cell> TileManifold::Grow(const std::optional<Cell>& seed,
                                                   double min_weight) {
  return impl_->Grow(seed, min_weight);
}
std::vector<TileManifold::Cell> TileManifold::FreeEnclosedCameras() {
  return impl_->FreeEnclosedCameras();
}
std::vector<TileManifold::Cell> TileManifold::JoinPockets() { return impl_->JoinPockets(); }
int64_t TileManifold::SetLabels(const std::vector<Cell>& cells, bool outside) {
  return impl_->SetLabels(cells, outside);
}
std::vector<CellRayCount> TileManifold::OwnedCounts() const { return impl_->OwnedCounts(); }
std::vector<TileManifold::Cell> TileManifold::OutsideCells() const { return impl_->OutsideCells(); }
std::vector<TileManifold::Face> TileManifold::SurfaceFaces() const { return impl_->SurfaceFaces(); }

}  // namespace ms
