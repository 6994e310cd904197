#include "manifold/cell_ray_counts.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <string>
#include <unordered_map>

#include "base/error.h"
#include "manifold/ray_walker.h"
#include "manifold/rays_through_box.h"
#include "manifold/triangulation.h"

namespace ms {

using manifold_detail::Cell_handle;
using manifold_detail::Delaunay;
using manifold_detail::KeyOf;
using manifold_detail::RayWalker;
using manifold_detail::ToPoint;

namespace {

Delaunay TriangulateHeld(const std::vector<Eigen::Vector3d>& points,
                         const std::vector<int32_t>& held) {
  std::vector<std::pair<manifold_detail::Point, manifold_detail::VertexInfo>> input;
  input.reserve(held.size());
  for (int32_t id : held) {
    if (id < 0 || static_cast<size_t>(id) >= points.size()) {
      throw InputError("held point id " + std::to_string(id) + " is out of range");
    }
    manifold_detail::VertexInfo info;
    info.id = id;
    input.emplace_back(ToPoint(points[id]), info);
  }
  Delaunay dt(input.begin(), input.end());
  if (dt.number_of_vertices() != held.size()) {
    throw InputError("the held points repeat a position (" + std::to_string(held.size()) +
                     " points, " + std::to_string(dt.number_of_vertices()) + " distinct)");
  }
  return dt;
}

}  // namespace

std::vector<CellRayCount> CountRaysOnCells(
    const std::vector<Eigen::Vector3d>& points, const std::vector<int32_t>& held,
    const std::vector<Eigen::Vector3d>& camera_centres, const std::vector<ViewingRay>& rays,
    const std::function<bool(const std::array<int32_t, 4>&)>& counted, CellRayCountStats* stats) {
  const auto start_time = std::chrono::steady_clock::now();
  CellRayCountStats local;
  if (stats == nullptr) stats = &local;
  const Delaunay dt = TriangulateHeld(points, held);
  if (dt.dimension() < 3) throw InputError("the held points span no volume");

  // The counted cells, and the box around them: a ray that misses the box crosses none.
  std::unordered_map<const void*, CellRayCount> counts;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    const std::array<int32_t, 4> ids = KeyOf(c);
    if (!counted(ids)) continue;
    counts[&*c].ids = ids;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d p = manifold_detail::ToEigen(c->vertex(i)->point());
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }

  RayWalker walker(dt, camera_centres.size());
  manifold_detail::LocateCamerasInside(camera_centres, &walker);
  const auto count = [&](const Cell_handle& c, unsigned camera_side) {
    const auto it = counts.find(&*c);
    if (it == counts.end()) return;
    CellRayCount& n = it->second;
    ++n.crossings;
    for (int i = 0; i < 4; ++i) {
      if (((camera_side >> i) & 1) == 0) continue;
      // Face i of the cell is opposite vertex i: its place among the ascending ids.
      const int32_t opposite = c->vertex(i)->info().id;
      n.camera_beyond[std::find(n.ids.begin(), n.ids.end(), opposite) - n.ids.begin()] += 1;
    }
  };
  if (counts.empty()) {
    stats->rays += static_cast<int64_t>(rays.size());  // none can cross a counted cell
  } else {
    manifold_detail::WalkRaysMeetingBox(points, camera_centres, rays, lo, hi, &walker, stats,
                                        count);
  }

  std::vector<CellRayCount> result;
  result.reserve(counts.size());
  for (const auto& [cell, n] : counts) result.push_back(n);
  std::sort(result.begin(), result.end(),
            [](const CellRayCount& a, const CellRayCount& b) { return a.ids < b.ids; });
  stats->seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

}  // namespace ms
