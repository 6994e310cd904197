// The free-space cut (--manifold.visibility cut, docs/design/manifold.md "The free-space cut"):
// every cell of the triangulation free or matter by a minimum s-t cut of the cell graph, as
// Labatut et al. ("Robust and efficient surface reconstruction from range data", 2009) and
// OpenMVS's ReconstructMesh weigh it, instead of the paper's threshold on each cell's weight.
//
// Source: the cells holding a camera. Sink: the cell each ray enters past its point, and the
// infinite cells. A ray crossing the face from cell a to cell b costs cutting a (free) from b
// (matter) there: 1 - exp(-d^2 / 2 sigma^2), d the crossing's distance to the point, so a ray
// may end a little behind the surface it was matched on. Every face costs quality x (1 - the
// smaller of the cosines of its circumspheres' angles with its plane): cheap where both cells
// have large empty balls on their sides, as a surface face between free space and matter does;
// dear across a thin cell that reaches from a facade's last points past its edge.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "base/log.h"
#include "manifold/manifold_impl.h"
#include "manifold/min_cut.h"

namespace ms {
namespace {

using manifold_detail::Cell_handle;
using manifold_detail::Delaunay;
using manifold_detail::ParallelWalks;
using manifold_detail::ToEigen;
using manifold_detail::Vertex_handle;
using manifold_detail::WalkScratch;

// Capacities are fixed point, so the cut is exact and the same for any order of the sums.
constexpr double kCapacityUnit = 1024.0;
constexpr int64_t kCameraCapacity = int64_t{1} << 40;

int64_t Capacity(double weight) { return std::llround(weight * kCapacityUnit); }

// The median length of the edges between input points (not Steiner points).
double MedianPointEdge(const Delaunay& dt) {
  std::vector<double> lengths;
  for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e) {
    const auto& a = e->first->vertex(e->second);
    const auto& b = e->first->vertex(e->third);
    if (a->info().id < 0 || b->info().id < 0) continue;
    lengths.push_back((ToEigen(a->point()) - ToEigen(b->point())).norm());
  }
  if (lengths.empty()) return 0;
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  return lengths[lengths.size() / 2];
}

// The cosine of the angle between face i's plane and c's circumsphere: positive when the
// circumcentre lies on c's side of the face (Labatut et al.'s beta-skeleton measure).
// The corners of face i of c.
std::array<Eigen::Vector3d, 3> FaceCorners(const Cell_handle& c, int i) {
  return {ToEigen(c->vertex((i + 1) & 3)->point()), ToEigen(c->vertex((i + 2) & 3)->point()),
          ToEigen(c->vertex((i + 3) & 3)->point())};
}

double FaceSphereCosine(const Cell_handle& c, int i, const Eigen::Vector3d& centre) {
  const auto [p0, p1, p2] = FaceCorners(c, i);
  Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
  if (normal.dot(ToEigen(c->vertex(i)->point()) - p0) < 0) normal = -normal;
  const double radius = (centre - p0).norm();
  const double length = normal.norm();
  if (radius == 0 || length == 0) return 0;
  return std::clamp(normal.dot(centre - p0) / (length * radius), -1.0, 1.0);
}

// Where the segment a -> b crosses the plane of face i of c, as the distance from b.
double CrossingDistanceToEnd(const Cell_handle& c, int i, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b) {
  const auto [p0, p1, p2] = FaceCorners(c, i);
  const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
  const double along = normal.dot(b - a);
  if (along == 0) return ((p0 + p1 + p2) / 3 - b).norm();
  const double t = std::clamp(normal.dot(p0 - a) / along, 0.0, 1.0);
  return (1 - t) * (b - a).norm();
}

}  // namespace

void DelaunayManifold::Impl::CutFreeSpace() {
  Timer timer;
  // The finite cells, numbered in the triangulation's order; a cell's number rides in its visit
  // stamp while the cut is built (the walks below use their own marks) and the stamps are
  // cleared after (0 is no walk's stamp).
  std::vector<Cell_handle> cells;
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    c->info().stamp = static_cast<uint32_t>(cells.size());
    cells.push_back(c);
  }
  const size_t n = cells.size();
  auto node = [&](const Cell_handle& c) {
    return dt_.is_infinite(c) ? -1 : static_cast<int32_t>(c->info().stamp);
  };
  std::vector<int64_t> from_source(n, 0), to_sink(n, 0);
  // Per cell and face: what cutting the cell (free) from its neighbour there (matter) costs.
  std::vector<std::array<int64_t, 4>> out_cost(n, {0, 0, 0, 0});

  for (int32_t camera = 0; camera < static_cast<int32_t>(cameras_.size()); ++camera) {
    for (const Cell_handle& c : walker_.StartCandidates(walker_.StartOf(camera))) {
      const int32_t k = node(c);
      if (k >= 0) from_source[k] = kCameraCapacity;
    }
  }

  const double sigma = options_.cut_thickness * MedianPointEdge(dt_);
  const double inv_two_sigma2 = sigma > 0 ? 0.5 / (sigma * sigma) : 0;
  // Each crossing adds a whole number of capacity units, atomically: the sums are the same on
  // any number of threads.
  walker_.LocateStarts();
  int64_t rays = 0;
  ray_index_->ForEachChunkInDirectionOrder(
      ParallelWalks::kChunk, [&](const std::vector<RayRef>& chunk) {
        walks_.Run(chunk.size(), [&](size_t i, auto& marks, WalkScratch& scratch, auto&) {
          const RayRef& ray = chunk[i];
          const Vertex_handle& target = vertex_of_point_[ray.point];
          const Eigen::Vector3d a = cameras_[ray.camera].center;
          const Eigen::Vector3d b = ToEigen(target->point());
          Cell_handle previous;
          return walker_.WalkFromCameraWith(
              ray.camera, target, marks, scratch, [&](const Cell_handle& c, unsigned) {
                int face = -1;
                if (previous != Cell_handle() && previous->has_neighbor(c, face)) {
                  const int32_t k = node(previous);
                  if (k >= 0) {
                    const double d = CrossingDistanceToEnd(previous, face, a, b);
                    const double cost = sigma > 0 ? 1 - std::exp(-d * d * inv_two_sigma2) : 1.0;
                    __atomic_fetch_add(&out_cost[k][face], Capacity(cost), __ATOMIC_RELAXED);
                  }
                }
                previous = c;
              });
        });
        rays += static_cast<int64_t>(chunk.size());
      });
  std::vector<Cell_handle> star;
  ray_index_->ForEachInDirectionOrder([&](const RayRef& ray) {
    const Cell_handle behind = CellBehindRay(ray, &star);
    const int32_t k = behind == Cell_handle() ? -1 : node(behind);
    if (k >= 0) to_sink[k] += Capacity(1.0);
  });
  const double seconds_rays = timer.Seconds();

  std::vector<manifold_detail::CutEdge> edges;
  edges.reserve(2 * n);
  std::vector<Eigen::Vector3d> centres(n);
  for (size_t k = 0; k < n; ++k) {
    const Cell_handle& c = cells[k];
    centres[k] = ToEigen(CGAL::circumcenter(c->vertex(0)->point(), c->vertex(1)->point(),
                                            c->vertex(2)->point(), c->vertex(3)->point()));
  }
  for (size_t k = 0; k < n; ++k) {
    const Cell_handle& c = cells[k];
    for (int i = 0; i < 4; ++i) {
      const Cell_handle other = c->neighbor(i);
      const int32_t m = node(other);
      if (m < 0) {
        // The infinite cells are matter: cutting the hull costs the face's rays.
        to_sink[k] += out_cost[k][i];
        continue;
      }
      if (m < static_cast<int32_t>(k)) continue;  // each pair once
      const int j = other->index(c);
      const double cos_here = FaceSphereCosine(c, i, centres[k]);
      const double cos_there = FaceSphereCosine(other, j, centres[m]);
      const int64_t quality = Capacity(options_.cut_quality * (1 - std::min(cos_here, cos_there)));
      edges.push_back(
          {static_cast<int32_t>(k), m, out_cost[k][i] + quality, out_cost[m][j] + quality});
    }
  }
  for (const Cell_handle& c : cells) c->info().stamp = 0;
  std::vector<std::array<int64_t, 4>>().swap(out_cost);
  std::vector<Eigen::Vector3d>().swap(centres);
  const std::vector<uint8_t> free = SourceSideOfMinCut(from_source, to_sink, edges);
  int64_t free_cells = 0;
  for (size_t k = 0; k < n; ++k) {
    labels_.SetCutVerdict(cells[k], free[k] != 0);
    free_cells += free[k];
  }
  spdlog::info(
      "manifold: free-space cut of {} cells ({} rays, sigma {:.3g}): {} free in {:.2f} s ({:.2f} "
      "s weighing the rays)",
      n, rays, sigma, free_cells, timer.Seconds(), seconds_rays);
}

}  // namespace ms
