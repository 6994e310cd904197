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
#include <set>
#include <string>
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

// A ball that surely holds a cell's closed circumball: the centre and squared radius are
// constructed exactly (lazily) and read as enclosing intervals, so even a flat cell, whose
// floating-point circumcentre may be far off, gets a ball that is large rather than wrong.
struct Ball {
  Eigen::Vector3d centre_lo, centre_hi;  // a box that holds the centre
  double radius = 0;                     // at least the radius
};
Ball CircumballBound(const Delaunay::Cell_handle& c) {
  std::array<Exact::Point_3, 4> p;
  for (int i = 0; i < 4; ++i) {
    const Point& q = c->vertex(i)->point();
    p[i] = Exact::Point_3(q.x(), q.y(), q.z());
  }
  const Exact::Point_3 centre = CGAL::circumcenter(p[0], p[1], p[2], p[3]);
  const double r2_high = CGAL::to_interval(CGAL::squared_distance(centre, p[0])).second;
  Ball ball;
  ball.radius = std::nextafter(std::sqrt(r2_high), std::numeric_limits<double>::infinity());
  for (int a = 0; a < 3; ++a) {
    const std::pair<double, double> x = CGAL::to_interval(centre.cartesian(a));
    ball.centre_lo[a] = x.first;
    ball.centre_hi[a] = x.second;
  }
  return ball;
}

// Whether the box [lo, hi] may meet the ball: false only when every point of the box is
// farther than the radius from every centre the ball allows.
bool MayMeet(const Ball& ball, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  double gap2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double gap = std::max({0.0, lo[a] - ball.centre_hi[a], ball.centre_lo[a] - hi[a]});
    gap2 += gap * gap;
  }
  // Slack for the rounding of the gaps.
  return gap2 <= ball.radius * ball.radius * (1 + 1e-9);
}

// The tiles whose regions may meet the ball (its bounding box rounded outwards).
std::vector<int> TilesTheBallMayMeet(const TileLayout& layout, const Ball& ball) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Eigen::Vector3d lo, hi;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::nextafter(ball.centre_lo[a] - ball.radius, -kInf);
    hi[a] = std::nextafter(ball.centre_hi[a] + ball.radius, kInf);
  }
  return layout.TilesMeeting(lo, hi);
}

// A tile's own points in a static k-d tree, for the sphere queries other tiles ask it. A
// query descends only into boxes the ball may meet, so the large, empty spheres of cells that
// reach out of the scene cost their boundary's points, not their bounding box's.
class PointIndex {
 public:
  PointIndex(const std::vector<Eigen::Vector3d>& points, std::vector<int32_t> ids)
      : points_(points), ids_(std::move(ids)) {
    if (!ids_.empty()) Build(0, ids_.size());
  }

  // Calls visit(id) for every point the ball may hold (a superset of those it holds).
  template <typename Visit>
  void ForEachIn(const Ball& ball, Visit&& visit) const {
    if (!nodes_.empty()) Visit1(0, ball, visit);
  }

 private:
  static constexpr size_t kLeafSize = 16;
  struct Node {
    Eigen::Vector3d lo, hi;
    size_t begin, end;
    int32_t low = -1, high = -1;  // children (-1: a leaf)
  };

  int32_t Build(size_t begin, size_t end) {
    const int32_t index = static_cast<int32_t>(nodes_.size());
    nodes_.push_back({points_[ids_[begin]], points_[ids_[begin]], begin, end});
    for (size_t i = begin; i < end; ++i) {
      nodes_[index].lo = nodes_[index].lo.cwiseMin(points_[ids_[i]]);
      nodes_[index].hi = nodes_[index].hi.cwiseMax(points_[ids_[i]]);
    }
    if (end - begin <= kLeafSize) return index;
    int axis = 0;
    (nodes_[index].hi - nodes_[index].lo).maxCoeff(&axis);
    const size_t middle = begin + (end - begin) / 2;
    std::nth_element(ids_.begin() + begin, ids_.begin() + middle, ids_.begin() + end,
                     [&](int32_t a, int32_t b) { return points_[a][axis] < points_[b][axis]; });
    const int32_t low = Build(begin, middle);
    const int32_t high = Build(middle, end);
    nodes_[index].low = low;
    nodes_[index].high = high;
    return index;
  }

  template <typename Visit>
  void Visit1(int32_t index, const Ball& ball, Visit& visit) const {
    const Node& node = nodes_[index];
    if (!MayMeet(ball, node.lo, node.hi)) return;
    if (node.low < 0) {
      for (size_t i = node.begin; i < node.end; ++i) visit(ids_[i]);
      return;
    }
    Visit1(node.low, ball, visit);
    Visit1(node.high, ball, visit);
  }

  const std::vector<Eigen::Vector3d>& points_;
  std::vector<int32_t> ids_;  // in tree order
  std::vector<Node> nodes_;
};

// One point in this many of the other tiles' (by id) starts in every tile.
constexpr int32_t kFirstSampleStride = 64;

struct TileState {
  Delaunay dt;
  std::vector<uint8_t> held;   // per point id
  std::vector<uint8_t> exact;  // per point id: its star must be the whole triangulation's
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

// The vertices whose stars the tile needs exact: its own points, whose stars hold its cells,
// and every vertex of its cells, whose stars decide whether a cell of its may flip while the
// surface stays manifold (the regularity test of growing).
void MarkStarsToMakeExact(const std::vector<int32_t>& owner, int tile, TileState* state) {
  state->exact.assign(owner.size(), 0);
  for (size_t id = 0; id < owner.size(); ++id) state->exact[id] = owner[id] == tile;
  for (auto c = state->dt.finite_cells_begin(); c != state->dt.finite_cells_end(); ++c) {
    if (owner[KeyOf(c)[0]] != tile) continue;
    for (int i = 0; i < 4; ++i) state->exact[c->vertex(i)->info()] = 1;
  }
}

}  // namespace

namespace {

// The cells of the tile's triangulation with a vertex whose star must be exact.
template <typename Visit>
void ForEachCellAroundExactStars(const TileState& tile, Visit&& visit) {
  for (auto c = tile.dt.finite_cells_begin(); c != tile.dt.finite_cells_end(); ++c) {
    bool around = false;
    for (int i = 0; i < 4; ++i) around = around || tile.exact[c->vertex(i)->info()];
    if (around) visit(c);
  }
}

// One tile's turn in a round: it asks the other tiles for their points in the circumball of
// every cell around its exact stars that it has not asked about yet, and queues the points in
// the ball for insertion. Returns whether it learnt one.
bool AskAboutNewCells(const std::vector<Eigen::Vector3d>& points, const TileLayout& layout,
                      const std::vector<PointIndex>& indexes, int t, TileState* tile,
                      StarExchangeStats* stats) {
  bool learnt = false;
  ForEachCellAroundExactStars(*tile, [&](const Delaunay::Cell_handle& c) {
    if (!tile->asked.insert(KeyOf(c)).second) return;
    ++stats->spheres_asked;
    const Ball ball = CircumballBound(c);
    const Point& p0 = c->vertex(0)->point();
    const Point& p1 = c->vertex(1)->point();
    const Point& p2 = c->vertex(2)->point();
    const Point& p3 = c->vertex(3)->point();
    for (int other : TilesTheBallMayMeet(layout, ball)) {
      if (other == t) continue;
      indexes[other].ForEachIn(ball, [&](int32_t id) {
        if (tile->held[id] || CGAL::side_of_bounded_sphere(p0, p1, p2, p3, ToPoint(points[id])) ==
                                  CGAL::ON_UNBOUNDED_SIDE) {
          return;
        }
        tile->held[id] = 1;
        tile->incoming.push_back(id);
        ++stats->points_sent;
        learnt = true;
      });
    }
  });
  return learnt;
}

// An own point on the tile's convex hull lies outside the hull points' hull.
void CheckInsideHull(const TileState& tile, const std::vector<uint8_t>& is_hull) {
  std::vector<Delaunay::Vertex_handle> on_hull;
  tile.dt.adjacent_vertices(tile.dt.infinite_vertex(), std::back_inserter(on_hull));
  for (const auto& v : on_hull) {
    if (!is_hull[v->info()]) {
      throw InputError("tiles: point " + std::to_string(v->info()) +
                       " lies outside the convex hull of the hull points");
    }
  }
}

// The other tiles' points a tile keeps: the vertices of its exact stars and the hull. Without
// the rest learnt on the way those stars' spheres stay empty, so the stars stay.
std::vector<int32_t> StarVertices(const std::vector<int32_t>& owner, int t,
                                  const std::vector<int32_t>& hull, const TileState& tile) {
  std::vector<uint8_t> needed(owner.size(), 0);
  ForEachCellAroundExactStars(tile, [&](const Delaunay::Cell_handle& c) {
    for (int i = 0; i < 4; ++i) needed[c->vertex(i)->info()] = 1;
  });
  for (int32_t id : hull) needed[id] = 1;
  std::vector<int32_t> foreign;
  for (size_t id = 0; id < owner.size(); ++id) {
    if (needed[id] && owner[id] != t) foreign.push_back(static_cast<int32_t>(id));
  }
  return foreign;
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
    if (id < 0 || id >= n) {
      throw InputError("tiles: hull point id " + std::to_string(id) + " out of range");
    }
    is_hull[id] = 1;
  }

  std::vector<TileState> state(tiles);
  std::vector<PointIndex> indexes;
  indexes.reserve(tiles);
  for (int t = 0; t < tiles; ++t) {
    indexes.emplace_back(points, holdings[t].owned);
    state[t].held.assign(n, 0);
    for (int32_t id : holdings[t].owned) state[t].held[id] = 1;
    state[t].incoming = holdings[t].owned;
    // The hull, and a sparse sample of the other tiles' points: without it the first
    // triangulation has cells across the empty rest of the scene whose spheres take in
    // everything there. Points not in a star at the end are let go again.
    for (int32_t id = 0; id < n; ++id) {
      if (!state[t].held[id] && (is_hull[id] || id % kFirstSampleStride == 0)) {
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
      MarkStarsToMakeExact(owner, t, &state[t]);
      learnt = AskAboutNewCells(points, layout, indexes, t, &state[t], &local) || learnt;
    }
  }
  for (int t = 0; t < tiles; ++t) {
    CheckInsideHull(state[t], is_hull);
    holdings[t].foreign = StarVertices(owner, t, hull, state[t]);
    local.foreign_points += static_cast<int64_t>(holdings[t].foreign.size());
  }
  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = local;
  return holdings;
}

namespace {

Delaunay TriangulateHolding(const std::vector<Eigen::Vector3d>& points,
                            const TileHolding& holding) {
  std::vector<std::pair<Point, int32_t>> batch;
  for (const auto* ids : {&holding.owned, &holding.foreign}) {
    for (int32_t id : *ids) batch.emplace_back(ToPoint(points[id]), id);
  }
  return Delaunay(batch.begin(), batch.end());
}

bool Owns(const TileHolding& holding, const TileCell& cell) {
  return std::binary_search(holding.owned.begin(), holding.owned.end(), cell[0]);
}

}  // namespace

std::vector<TileCell> OwnedCells(const std::vector<Eigen::Vector3d>& points,
                                 const TileHolding& holding) {
  const Delaunay dt = TriangulateHolding(points, holding);
  std::vector<TileCell> cells;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    const TileCell key = KeyOf(c);
    if (Owns(holding, key)) cells.push_back(key);
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

std::vector<TileCell> CellsAroundOwnedCells(const std::vector<Eigen::Vector3d>& points,
                                            const TileHolding& holding) {
  const Delaunay dt = TriangulateHolding(points, holding);
  std::unordered_set<int32_t> vertices(holding.owned.begin(), holding.owned.end());
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    const TileCell key = KeyOf(c);
    if (Owns(holding, key)) vertices.insert(key.begin(), key.end());
  }
  std::vector<TileCell> cells;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    const TileCell key = KeyOf(c);
    if (std::any_of(key.begin(), key.end(), [&](int32_t id) { return vertices.count(id); })) {
      cells.push_back(key);
    }
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

std::vector<std::vector<int>> TileNeighbours(const std::vector<Eigen::Vector3d>& points,
                                             const std::vector<TileHolding>& holdings,
                                             const TileLayout& layout) {
  std::vector<std::vector<int>> neighbours(holdings.size());
  for (size_t t = 0; t < holdings.size(); ++t) {
    std::set<int> found;
    for (const TileCell& cell : CellsAroundOwnedCells(points, holdings[t])) {
      const int owner = layout.TileOf(points[cell[0]]);
      if (owner != static_cast<int>(t)) found.insert(owner);
    }
    neighbours[t].assign(found.begin(), found.end());
  }
  // Symmetric: a tile that reads another's labels is read by it for the same stars' sake.
  for (size_t t = 0; t < holdings.size(); ++t) {
    for (int other : neighbours[t]) {
      auto& back = neighbours[other];
      if (!std::binary_search(back.begin(), back.end(), static_cast<int>(t))) {
        back.insert(std::upper_bound(back.begin(), back.end(), static_cast<int>(t)),
                    static_cast<int>(t));
      }
    }
  }
  return neighbours;
}

std::vector<int> ColourTiles(const std::vector<std::vector<int>>& neighbours) {
  std::vector<int> colour(neighbours.size(), -1);
  for (size_t t = 0; t < neighbours.size(); ++t) {
    std::set<int> taken;
    for (int other : neighbours[t]) {
      if (colour[other] >= 0) taken.insert(colour[other]);
    }
    int c = 0;
    while (taken.count(c)) ++c;
    colour[t] = c;
  }
  return colour;
}

}  // namespace ms
