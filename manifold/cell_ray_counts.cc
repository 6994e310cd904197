#include "manifold/cell_ray_counts.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <string>
#include <unordered_map>

#include "base/error.h"
#include "manifold/cell_predicates.h"
#include "manifold/ray_walker.h"
#include "manifold/triangulation.h"

namespace ms {

using manifold_detail::Cell_handle;
using manifold_detail::Delaunay;
using manifold_detail::KeyOf;
using manifold_detail::RayWalker;
using manifold_detail::StampMarks;
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
  walker.LocateCameras(camera_centres);
  for (size_t c = 0; c < camera_centres.size(); ++c) {
    const manifold_detail::CameraStart& start = walker.StartOf(static_cast<int>(c));
    if (start.type == Delaunay::OUTSIDE_CONVEX_HULL ||
        start.type == Delaunay::OUTSIDE_AFFINE_HULL) {
      throw InputError("camera " + std::to_string(c) + " lies outside the held points' hull");
    }
  }
  StampMarks marks(&walker);
  manifold_detail::WalkScratch scratch;
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
  for (const ViewingRay& ray : rays) {
    ++stats->rays;
    if (ray.camera < 0 || static_cast<size_t>(ray.camera) >= camera_centres.size() ||
        ray.point < 0 || static_cast<size_t>(ray.point) >= points.size()) {
      throw InputError("viewing ray (camera " + std::to_string(ray.camera) + ", point " +
                       std::to_string(ray.point) + ") is out of range");
    }
    double entry = 0;
    if (counts.empty() || !manifold_detail::SegmentMeetsBox(camera_centres[ray.camera],
                                                            points[ray.point], lo, hi, &entry)) {
      continue;
    }
    ++stats->rays_walked;
    stats->cell_steps +=
        walker.WalkToPointWith(walker.StartOf(ray.camera), walker.camera_point(ray.camera),
                               ToPoint(points[ray.point]), marks, scratch, count);
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
