// The one CGAL translation unit of tiles/.
#include "tiles/tile_stars.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "base/error.h"

namespace ms {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_3;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int32_t, Kernel>;
using Tds = CGAL::Triangulation_data_structure_3<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;

Point ToPoint(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }

TileCell KeyOf(const Delaunay::Cell_handle& c) {
  TileCell key;
  for (int i = 0; i < 4; ++i) key[i] = c->vertex(i)->info();
  std::sort(key.begin(), key.end());
  return key;
}

struct CellHash {
  size_t operator()(const TileCell& k) const {
    uint64_t h = 1469598103934665603ull;
    for (int32_t v : k) h = (h ^ static_cast<uint32_t>(v)) * 1099511628211ull;
    return h;
  }
};

// A box that surely holds a cell's closed circumball: the centre and squared radius are
// constructed exactly (lazily) and read as enclosing intervals, so even a flat cell, whose
// floating-point circumcentre may be far off, gets a box that is large rather than wrong.
struct Box {
  Eigen::Vector3d lo, hi;
};
Box CircumballBox(const Delaunay::Cell_handle& c) {
  std::array<Exact::Point_3, 4> p;
  for (int i = 0; i < 4; ++i) {
    const Point& q = c->vertex(i)->point();
    p[i] = Exact::Point_3(q.x(), q.y(), q.z());
  }
  const Exact::Point_3 centre = CGAL::circumcenter(p[0], p[1], p[2], p[3]);
  const double r2_high = CGAL::to_interval(CGAL::squared_distance(centre, p[0])).second;
  const double r = std::nextafter(std::sqrt(r2_high), std::numeric_limits<double>::infinity());
  Box box;
  for (int a = 0; a < 3; ++a) {
    const std::pair<double, double> x = CGAL::to_interval(centre.cartesian(a));
    box.lo[a] = std::nextafter(x.first - r, -std::numeric_limits<double>::infinity());
    box.hi[a] = std::nextafter(x.second + r, std::numeric_limits<double>::infinity());
  }
  return box;
}

// A tile's own points, bucketed for box queries (the sphere queries other tiles ask it).
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector3d>& points, const std::vector<int32_t>& ids)
      : points_(points) {
    if (ids.empty()) return;
    lo_ = hi_ = points[ids[0]];
    for (int32_t id : ids) {
      lo_ = lo_.cwiseMin(points[id]);
      hi_ = hi_.cwiseMax(points[id]);
    }
    // About 8 points a bucket along the largest extent's scale.
    const double extent = (hi_ - lo_).maxCoeff();
    step_ = extent > 0 ? 2 * extent / std::cbrt(static_cast<double>(ids.size())) : 1.0;
    for (int32_t id : ids) buckets_[Key(Index(points[id]))].push_back(id);
  }

  // Calls visit(id) for every point in the closed box (and possibly a few more).
  template <typename Visit>
  void ForEachIn(const Box& box, Visit&& visit) const {
    if (buckets_.empty()) return;
    const Eigen::Vector3d lo = box.lo.cwiseMax(lo_), hi = box.hi.cwiseMin(hi_);
    if ((lo.array() > hi.array()).any()) return;
    const Eigen::Vector3i a = Index(lo), b = Index(hi);
    const double span =
        static_cast<double>(b.x() - a.x() + 1) * (b.y() - a.y() + 1) * (b.z() - a.z() + 1);
    if (span > static_cast<double>(buckets_.size())) {
      for (const auto& [key, ids] : buckets_) {
        for (int32_t id : ids) visit(id);
      }
      return;
    }
    for (int x = a.x(); x <= b.x(); ++x) {
      for (int y = a.y(); y <= b.y(); ++y) {
        for (int z = a.z(); z <= b.z(); ++z) {
          auto it = buckets_.find(Key(Eigen::Vector3i(x, y, z)));
          if (it == buckets_.end()) continue;
          for (int32_t id : it->second) visit(id);
        }
      }
    }
  }

 private:
  Eigen::Vector3i Index(const Eigen::Vector3d& p) const {
    return ((p - lo_) / step_).array().floor().cast<int>();
  }
  static int64_t Key(const Eigen::Vector3i& i) {
    return (static_cast<int64_t>(i.x()) << 42) ^ (static_cast<int64_t>(i.y()) << 21) ^ i.z();
  }

  const std::vector<Eigen::Vector3d>& points_;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero(), hi_ = Eigen::Vector3d::Zero();
  double step_ = 1;
  std::unordered_map<int64_t, std::vector<int32_t>> buckets_;
};

struct TileState {
  Delaunay dt;
  std::vector<uint8_t> held;  // per point id
  std::unordered_set<TileCell, CellHash> asked;
  std::vector<int32_t> incoming;  // points learnt this round, to insert next
};

void InsertHeld(const std::vector<Eigen::Vector3d>& points, TileState* tile) {
  std::vector<std::pair<Point, int32_t>> batch;
  batch.reserve(tile->incoming.size());
  for (int32_t id : tile->incoming) batch.emplace_back(ToPoint(points[id]), id);
  const size_t before = tile->dt.number_of_vertices();
  tile->dt.insert(batch.begin(), batch.end());
  if (tile->dt.number_of_vertices() != before + batch.size()) {
    throw InputError("tiles: two points at the same position (merge duplicates first)");
  }
  tile->incoming.clear();
}

}  // namespace

std::vector<TileHolding> ExchangeStarPoints(const std::vector<Eigen::Vector3d>& points,
                                            const std::vector<int32_t>& hull,
                                            const TileLayout& layout, StarExchangeStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  const int tiles = layout.num_tiles();
  const int32_t n = static_cast<int32_t>(points.size());
  std::vector<int32_t> owner(n);
  std::vector<TileHolding> holdings(tiles);
  for (int32_t id = 0; id < n; ++id) {
    owner[id] = layout.TileOf(points[id]);
    holdings[owner[id]].owned.push_back(id);
  }
  std::vector<uint8_t> is_hull(n, 0);
  for (int32_t id : hull) {
    if (id < 0 || id >= n)
      throw InputError("tiles: hull point id " + std::to_string(id) + " out of range");
    is_hull[id] = 1;
  }

  std::vector<TileState> state(tiles);
  std::vector<PointGrid> grids;
  grids.reserve(tiles);
  for (int t = 0; t < tiles; ++t) {
    grids.emplace_back(points, holdings[t].owned);
    state[t].held.assign(n, 0);
    for (int32_t id : holdings[t].owned) state[t].held[id] = 1;
    state[t].incoming = holdings[t].owned;
    for (int32_t id : hull) {
      if (!state[t].held[id]) {
        state[t].held[id] = 1;
        state[t].incoming.push_back(id);
      }
    }
  }

  StarExchangeStats local;
  for (bool learnt = true; learnt;) {
    learnt = false;
    ++local.rounds;
    for (int t = 0; t < tiles; ++t) InsertHeld(points, &state[t]);
    for (int t = 0; t < tiles; ++t) {
      TileState& tile = state[t];
      for (auto c = tile.dt.finite_cells_begin(); c != tile.dt.finite_cells_end(); ++c) {
        bool own = false;
        for (int i = 0; i < 4; ++i) own = own || owner[c->vertex(i)->info()] == t;
        if (!own || !tile.asked.insert(KeyOf(c)).second) continue;
        ++local.spheres_asked;
        const Box box = CircumballBox(c);
        const Point& p0 = c->vertex(0)->point();
        const Point& p1 = c->vertex(1)->point();
        const Point& p2 = c->vertex(2)->point();
        const Point& p3 = c->vertex(3)->point();
        for (int other : layout.TilesMeeting(box.lo, box.hi)) {
          if (other == t) continue;
          grids[other].ForEachIn(box, [&](int32_t id) {
            if (tile.held[id]) return;
            if (CGAL::side_of_bounded_sphere(p0, p1, p2, p3, ToPoint(points[id])) ==
                CGAL::ON_UNBOUNDED_SIDE) {
              return;
            }
            tile.held[id] = 1;
            tile.incoming.push_back(id);
            ++local.points_sent;
            learnt = true;
          });
        }
      }
    }
  }

  for (int t = 0; t < tiles; ++t) {
    // An owned point on the tile's convex hull is outside the hull points' hull.
    std::vector<Delaunay::Vertex_handle> on_hull;
    state[t].dt.adjacent_vertices(state[t].dt.infinite_vertex(), std::back_inserter(on_hull));
    for (const auto& v : on_hull) {
      if (!is_hull[v->info()]) {
        throw InputError("tiles: point " + std::to_string(v->info()) +
                         " lies outside the convex hull of the hull points");
      }
    }
    for (int32_t id = 0; id < n; ++id) {
      if (state[t].held[id] && owner[id] != t) holdings[t].foreign.push_back(id);
    }
    local.foreign_points += static_cast<int64_t>(holdings[t].foreign.size());
  }
  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = local;
  return holdings;
}

std::vector<TileCell> OwnedCells(const std::vector<Eigen::Vector3d>& points,
                                 const TileHolding& holding) {
  std::vector<std::pair<Point, int32_t>> batch;
  for (const auto* ids : {&holding.owned, &holding.foreign}) {
    for (int32_t id : *ids) batch.emplace_back(ToPoint(points[id]), id);
  }
  Delaunay dt(batch.begin(), batch.end());
  std::vector<TileCell> cells;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    const TileCell key = KeyOf(c);
    if (std::binary_search(holding.owned.begin(), holding.owned.end(), key[0])) {
      cells.push_back(key);
    }
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

}  // namespace ms
