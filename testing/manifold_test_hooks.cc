// Test hooks (testing/manifold_test_hooks.h): compiled into manifold_test only, never into the
// ms_manifold library. They reach DelaunayManifold::Impl through the internal headers.
#include "testing/manifold_test_hooks.h"

#include <algorithm>
#include <functional>
#include <iterator>
#include <thread>
#include <unordered_set>
#include <utility>
#include <vector>

#include "base/check.h"
#include "manifold/cell_predicates.h"
#include "manifold/manifold_impl.h"

namespace ms {

using manifold_detail::Cell_handle;
using manifold_detail::Delaunay;
using manifold_detail::KeyOf;
using manifold_detail::Point;
using manifold_detail::SegmentCrossesCell;
using manifold_detail::ToPoint;
using manifold_detail::Vertex_handle;
using manifold_detail::VertexInfo;

namespace manifold_internal {
namespace {

Delaunay Triangulate(const std::vector<Eigen::Vector3d>& points) {
  std::vector<std::pair<Point, VertexInfo>> vertices;
  for (size_t i = 0; i < points.size(); ++i) {
    vertices.push_back({ToPoint(points[i]), {static_cast<int32_t>(i), 0, 0, 0, 0}});
  }
  Delaunay dt(vertices.begin(), vertices.end());
  return dt;
}

}  // namespace

bool SegmentCrossesTetrahedron(std::array<Eigen::Vector3d, 4> tet, const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b) {
  std::vector<Eigen::Vector3d> points(tet.begin(), tet.end());
  Delaunay dt = Triangulate(points);
  MS_CHECK(dt.number_of_finite_cells() == 1) << "degenerate tetrahedron";
  return SegmentCrossesCell(dt.finite_cells_begin(), ToPoint(a), ToPoint(b));
}

std::vector<CellVertices> DelaunayCells(const std::vector<Eigen::Vector3d>& points) {
  Delaunay dt = Triangulate(points);
  std::vector<CellVertices> cells;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    cells.push_back(KeyOf(c));
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

SpreadCounts CountSpreads(int64_t rays, int threads) {
  Delaunay dt =
      Triangulate({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {0.9, 0.8, -0.3}});
  ManifoldOptions options;
  options.w1 = 1;
  options.w2 = 1;
  manifold_detail::CellLabels labels(dt, options);
  Cell_handle cell;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end() && cell == Cell_handle(); ++c) {
    if (!dt.is_infinite(c->neighbor(0))) cell = c;
  }
  MS_CHECK(cell != Cell_handle()) << "no finite cell with a finite neighbour";
  if (threads <= 1) {
    for (int64_t k = 0; k < rays; ++k) labels.CountCrossing(cell, 0x1);
  } else {
    std::vector<manifold_detail::CellLabels::OverflowTally> tallies(threads);
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&, t] {
        for (int64_t k = t; k < rays; k += threads) {
          labels.CountCrossingConcurrently(cell, 0x1, &tallies[t]);
        }
      });
    }
    for (std::thread& t : pool) t.join();
    for (const auto& tally : tallies) labels.MergeOverflow(tally);
  }
  SpreadCounts counts;
  counts.spread = labels.Spread(cell, 0);
  counts.neighbour_weight = labels.Weight(cell->neighbor(0));
  labels.ForgetCounts(cell);
  cell->info() = manifold_detail::CellInfo{};
  labels.CountCrossing(cell, 0x1);
  counts.after_forget = labels.Spread(cell, 0);
  return counts;
}

}  // namespace manifold_internal

// Friend of DelaunayManifold::Impl for the hooks that need its internals.
struct ManifoldTestAccess {
  static bool IsVertexRegular(const std::vector<Eigen::Vector3d>& points,
                              const std::vector<manifold_internal::CellVertices>& outside,
                              int32_t v) {
    DelaunayManifold::Impl impl({}, ManifoldOptions{});
    impl.dt_ = manifold_internal::Triangulate(points);
    Vertex_handle vertex;
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      if (std::binary_search(outside.begin(), outside.end(), KeyOf(c))) {
        impl.labels_.SetOutside(c, true);
      }
    }
    for (auto it = impl.dt_.finite_vertices_begin(); it != impl.dt_.finite_vertices_end(); ++it) {
      if (it->info().id == v) vertex = it;
    }
    MS_CHECK(vertex != Vertex_handle()) << "no vertex " << v;
    return impl.regularity_.VertexRegular(vertex, Cell_handle());
  }

  // Random O sets (random flips that keep the surface manifold), then both regularity tests
  // on every vertex of random cells: they must agree.
  static int64_t RegularityTestMismatches(const std::vector<Eigen::Vector3d>& points, uint32_t seed,
                                          int64_t* checked) {
    DelaunayManifold::Impl impl({}, ManifoldOptions{});
    std::vector<RayPoint> rays(points.size());
    for (size_t i = 0; i < points.size(); ++i) rays[i].position = points[i];
    impl.Build(rays);
    std::vector<Cell_handle> cells;
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      cells.push_back(c);
    }
    uint64_t state = seed * 2654435761u + 1;
    const auto next = [&]() {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<size_t>(state >> 33);
    };
    int64_t mismatches = 0;
    *checked = 0;
    for (int step = 0; step < 4000; ++step) {
      const Cell_handle t = cells[next() % cells.size()];
      bool fast = true, full = true;
      for (int i = 0; i < 4; ++i) {
        const bool a = impl.regularity_.VertexRegularAfterFlip(t->vertex(i), t);
        const bool b = impl.regularity_.VertexRegular(t->vertex(i), t);
        mismatches += a != b;
        ++*checked;
        fast &= a;
        full &= b;
      }
      if (fast && full) impl.labels_.SetOutside(t, !t->info().outside);
    }
    return mismatches;
  }

  static manifold_internal::LinkWalkComparison CompareLinkWalk(
      const std::vector<Eigen::Vector3d>& points,
      const std::function<bool(const Eigen::Vector3d&)>& in_o) {
    DelaunayManifold::Impl impl({}, ManifoldOptions{});
    impl.dt_ = manifold_internal::Triangulate(points);
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int i = 0; i < 4; ++i) centroid += manifold_detail::ToEigen(c->vertex(i)->point()) / 4;
      if (in_o(centroid)) impl.labels_.SetOutside(c, true);
    }
    manifold_internal::LinkWalkComparison result;
    std::vector<Cell_handle> star;
    for (auto v = impl.dt_.finite_vertices_begin(); v != impl.dt_.finite_vertices_end(); ++v) {
      star.clear();
      impl.dt_.incident_cells(v, std::back_inserter(star));
      const bool exhaustive = impl.regularity_.VertexRegular(v, Cell_handle());
      const bool from_star = impl.regularity_.VertexRegularByLinkWalk(v, star);
      const bool from_one = impl.regularity_.VertexRegularByLinkWalk(v, {star.back()});
      result.checked += 2;
      result.mismatches += (from_star != exhaustive) + (from_one != exhaustive);
      ++(exhaustive ? result.regular : result.irregular);
      if (static_cast<int64_t>(star.size()) > result.largest_star) {
        result.largest_star = static_cast<int64_t>(star.size());
        result.largest_star_regular = exhaustive;
      }
    }
    return result;
  }

  static manifold_internal::PinchJoinCounts JoinPocketsWithPinches(
      const std::vector<ManifoldCamera>& cameras, const std::vector<RayPoint>& points,
      uint32_t seed) {
    DelaunayManifold::Impl impl(cameras, ManifoldOptions{});
    impl.Build(points);
    uint64_t state = seed * 2654435761u + 7;
    std::vector<Cell_handle> o_cells;
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      if (c->info().outside && (state >> 33) % 3 == 0) o_cells.push_back(c);
    }
    for (const Cell_handle& c : o_cells) {
      if (impl.regularity_.FlipKeepsManifold(c)) impl.labels_.SetOutside(c, false);
    }
    manifold_internal::PinchJoinCounts counts;
    const int64_t whole_pieces_before = impl.grow_shrink_.whole_pieces_tried();  // by Build
    const uint32_t stamp = impl.walker_.NextStamp();
    for (const Cell_handle& seed_cell :
         impl.grow_shrink_.BoundarySeeds(RegrowSeeds::kBoundary, 0)) {
      const std::vector<Cell_handle> pocket = impl.grow_shrink_.Pocket(seed_cell, 1 << 16, stamp);
      if (pocket.empty()) continue;
      ++counts.pockets;
      const int64_t outside_before = impl.labels_.outside_count();
      const std::vector<Cell_handle> joined = impl.grow_shrink_.JoinPocketWithPinches(pocket, 8);
      if (joined.empty()) {
        ++counts.failed;
        counts.problems += impl.labels_.outside_count() != outside_before;
        continue;
      }
      (joined.size() > pocket.size() ? counts.with_pieces : counts.whole) += 1;
      for (const Cell_handle& c : pocket) counts.problems += !c->info().outside;
      counts.problems += !impl.ValidateManifold().empty() || !impl.ValidateLabels().empty();
    }
    counts.whole_piece_rounds = impl.grow_shrink_.whole_pieces_tried() - whole_pieces_before;
    return counts;
  }

  static manifold_internal::KeptRefusalsComparison CompareKeptRefusals(
      const std::vector<ManifoldCamera>& cameras, const std::vector<RayPoint>& points,
      uint32_t seed) {
    using manifold_detail::GrowShrink;
    DelaunayManifold::Impl kept(cameras, ManifoldOptions{});
    DelaunayManifold::Impl requeued(cameras, ManifoldOptions{});
    kept.Build(points);
    requeued.Build(points);
    // The two triangulations are the same; cells are paired by key.
    const auto by_key = [](DelaunayManifold::Impl& impl) {
      std::vector<std::pair<manifold_detail::CellKey, Cell_handle>> cells;
      for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
        cells.emplace_back(KeyOf(c), c);
      }
      std::sort(cells.begin(), cells.end());
      return cells;
    };
    const auto kept_cells = by_key(kept), requeued_cells = by_key(requeued);
    MS_CHECK(kept_cells.size() == requeued_cells.size()) << "the two builds differ";
    const auto pair_of = [&](const Cell_handle& c) {
      const auto at = std::lower_bound(kept_cells.begin(), kept_cells.end(),
                                       std::make_pair(KeyOf(c), Cell_handle()));
      MS_CHECK(at != kept_cells.end() && at->first == KeyOf(c)) << "no such cell";
      return requeued_cells[at - kept_cells.begin()].second;
    };
    const auto pairs_of = [&](const std::vector<Cell_handle>& cells) {
      std::vector<Cell_handle> paired;
      for (const Cell_handle& c : cells) paired.push_back(pair_of(c));
      return paired;
    };
    uint64_t state = seed * 2654435761u + 1;
    const auto next = [&]() {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<size_t>(state >> 33);
    };
    manifold_internal::KeptRefusalsComparison result;
    GrowShrink::Refusals indexed(GrowShrink::Refusals::Kind::kIndexed);
    GrowShrink::Refusals requeue(GrowShrink::Refusals::Kind::kRequeued);
    // Grows both from `seeds` (cells of `kept`) and compares the cells joined, in order.
    const auto grow = [&](const std::vector<Cell_handle>& seeds) {
      std::vector<Cell_handle> added_kept, added_requeued;
      kept.grow_shrink_.Grow(seeds, &added_kept, &indexed);
      requeued.grow_shrink_.Grow(pairs_of(seeds), &added_requeued, &requeue);
      for (size_t i = 0; i < std::max(added_kept.size(), added_requeued.size()); ++i) {
        result.order_mismatches += i >= added_kept.size() || i >= added_requeued.size() ||
                                   KeyOf(added_kept[i]) != KeyOf(added_requeued[i]);
      }
      result.grown += static_cast<int64_t>(added_kept.size());
    };
    // Takes up to 12 face-connected cells of O out, from a, where the surface stays manifold.
    const auto shrink = [&](const Cell_handle& a) {
      std::vector<Cell_handle> front = {a}, out;
      for (size_t f = 0; f < front.size() && out.size() < 12; ++f) {
        const Cell_handle x = front[f];
        if (!x->info().outside || !kept.regularity_.FlipKeepsManifold(x)) continue;
        kept.labels_.SetOutside(x, false);
        requeued.labels_.SetOutside(pair_of(x), false);
        out.push_back(x);
        for (int i = 0; i < 4; ++i) front.push_back(x->neighbor(i));
      }
      return out;
    };
    // O shrunk at a third of its cells, then grown back from its boundary in four parts: each
    // part's growing changes the labels around the refusals of the parts before, and so do
    // cells joined singly between the parts (FlipAllIfRegular, notified as a regrowing's
    // pocket joins are).
    std::vector<Cell_handle> o_cells;
    for (const auto& [key, c] : kept_cells) {
      if (c->info().outside && next() % 3 == 0) o_cells.push_back(c);
    }
    for (const Cell_handle& c : o_cells) shrink(c);
    std::vector<std::vector<Cell_handle>> parts(4);
    for (const Cell_handle& c : kept.grow_shrink_.BoundarySeeds(RegrowSeeds::kBoundary, 0)) {
      parts[next() % parts.size()].push_back(c);
    }
    parts.emplace_back();  // the last growing starts from what the last joins woke
    for (const std::vector<Cell_handle>& part : parts) {
      grow(part);
      const std::vector<Cell_handle> next_to_o =
          kept.grow_shrink_.BoundarySeeds(RegrowSeeds::kBoundary, 0);
      for (int attempt = 0; attempt < 20 && !next_to_o.empty(); ++attempt) {
        const Cell_handle a = next_to_o[next() % next_to_o.size()];
        if (!kept.grow_shrink_.NextToO(a)) continue;
        const bool joined = kept.grow_shrink_.FlipAllIfRegular({a});
        if (joined != requeued.grow_shrink_.FlipAllIfRegular({pair_of(a)})) {
          ++result.label_mismatches;  // the two have diverged already
          continue;
        }
        if (!joined) continue;
        ++result.joins;
        indexed.Flipped({a});
      }
    }
    result.refusals = static_cast<int64_t>(indexed.size());
    // Then cells of O taken out, each time followed by growing.
    for (int attempt = 0; attempt < 300; ++attempt) {
      const std::vector<Cell_handle> flipped =
          shrink(kept_cells[next() % kept_cells.size()].second);
      if (flipped.empty()) continue;
      result.shrinks += static_cast<int64_t>(flipped.size());
      std::vector<Cell_handle> seeds = kept.grow_shrink_.NextToOBeside(flipped);
      for (const Cell_handle& c : flipped) {
        if (kept.grow_shrink_.NextToO(c)) seeds.push_back(c);
      }
      indexed.Flipped(flipped);
      grow(seeds);
    }
    for (size_t k = 0; k < kept_cells.size(); ++k) {
      result.label_mismatches +=
          kept_cells[k].second->info().outside != requeued_cells[k].second->info().outside;
    }
    return result;
  }

  static void CrossedCells(const std::vector<Eigen::Vector3d>& points,
                           const Eigen::Vector3d& camera, int32_t target,
                           std::vector<manifold_internal::CellVertices>* walked,
                           std::vector<manifold_internal::CellVertices>* brute_force) {
    ManifoldCamera cam;
    cam.center = camera;
    DelaunayManifold::Impl impl({cam}, ManifoldOptions{});
    std::vector<RayPoint> rays(points.size());
    for (size_t i = 0; i < points.size(); ++i) rays[i].position = points[i];
    impl.Build(rays);
    const Point a = impl.walker_.camera_point(0);
    const Point b = impl.vertex_of_point_[target]->point();
    walked->clear();
    impl.walker_.WalkFromCamera(
        0, impl.vertex_of_point_[target],
        [&](const Cell_handle& c, unsigned) { walked->push_back(KeyOf(c)); });
    brute_force->clear();
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      if (SegmentCrossesCell(c, a, b)) brute_force->push_back(KeyOf(c));
    }
    std::sort(walked->begin(), walked->end());
    std::sort(brute_force->begin(), brute_force->end());
  }
};

namespace manifold_internal {

int64_t RegularityTestMismatches(const std::vector<Eigen::Vector3d>& points, uint32_t seed,
                                 int64_t* checked) {
  return ManifoldTestAccess::RegularityTestMismatches(points, seed, checked);
}

bool IsVertexRegular(const std::vector<Eigen::Vector3d>& points,
                     const std::vector<CellVertices>& outside, int32_t v) {
  std::vector<CellVertices> sorted = outside;
  std::sort(sorted.begin(), sorted.end());
  return ManifoldTestAccess::IsVertexRegular(points, sorted, v);
}

LinkWalkComparison CompareLinkWalk(const std::vector<Eigen::Vector3d>& points,
                                   const std::function<bool(const Eigen::Vector3d&)>& in_o) {
  return ManifoldTestAccess::CompareLinkWalk(points, in_o);
}

KeptRefusalsComparison CompareKeptRefusals(const std::vector<ManifoldCamera>& cameras,
                                           const std::vector<RayPoint>& points, uint32_t seed) {
  return ManifoldTestAccess::CompareKeptRefusals(cameras, points, seed);
}

PinchJoinCounts JoinPocketsWithPinches(const std::vector<ManifoldCamera>& cameras,
                                       const std::vector<RayPoint>& points, uint32_t seed) {
  return ManifoldTestAccess::JoinPocketsWithPinches(cameras, points, seed);
}

void CrossedCells(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& camera,
                  int32_t target, std::vector<CellVertices>* walked,
                  std::vector<CellVertices>* brute_force) {
  ManifoldTestAccess::CrossedCells(points, camera, target, walked, brute_force);
}

}  // namespace manifold_internal
}  // namespace ms
