// DelaunayManifold::Validate, layer by layer: the triangulation, then the labels (O and the
// per-vertex counts), then the manifold (every vertex regular), then the weights (the ray
// counts against a recount), then, with the paper's regrowing, that O is maximal. Each layer
// assumes the ones before it hold, so it runs only when they passed (as CGAL's is_valid checks the
// data structure first); the first layer with a problem names it. Every message ends in "; ".
#include <array>
#include <sstream>
#include <string>
#include <unordered_map>

#include "manifold/manifold_impl.h"

namespace ms {

using manifold_detail::CameraStart;

std::string DelaunayManifold::Impl::Validate(bool check_weights) {
  std::string problems = ValidateTriangulation();
  if (problems.empty()) problems = ValidateLabels();
  if (problems.empty()) problems = ValidateManifold();
  if (problems.empty() && check_weights) problems = ValidateWeights();
  // Growing from every boundary cell leaves no free cell that could still join O; regrowing
  // only near the batch does not promise it.
  if (problems.empty() && options_.regrow_seeds == RegrowSeeds::kBoundary) {
    problems = ValidateMaximal();
  }
  return problems;
}

// No free cell sharing a face with O could flip into O with the surface staying manifold.
std::string DelaunayManifold::Impl::ValidateMaximal() {
  std::vector<manifold_detail::Cell_handle> first;
  const int64_t joinable = grow_shrink_.CountJoinableCells(&first, 1);
  if (joinable == 0) return "";
  std::ostringstream problem;
  problem << "O is not maximal: " << joinable
          << " free cells on its boundary could join it keeping the surface manifold (one has "
             "weight "
          << labels_.Weight(first.front()) << "); ";
  return problem.str();
}

std::string DelaunayManifold::Impl::ValidateTriangulation() const {
  if (!dt_.is_valid(false)) return "CGAL triangulation invalid; ";
  return "";
}

// No infinite cell in O, |O| as counted, and every vertex's counts (cells, cells in O, surface
// faces) as counted.
std::string DelaunayManifold::Impl::ValidateLabels() const {
  std::ostringstream problems;
  std::unordered_map<const void*, int32_t> outside_cells, cells_around, surface_faces;
  int64_t outside = 0;
  for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
    for (int i = 0; i < 4; ++i) ++cells_around[&*c->vertex(i)];
    if (!c->info().outside) continue;
    for (int i = 0; i < 4; ++i) {
      if (labels_.InO(c->neighbor(i))) continue;
      for (int j = 0; j < 4; ++j) {
        if (j != i) ++surface_faces[&*c->vertex(j)];
      }
    }
    if (dt_.is_infinite(c)) {
      problems << "an infinite cell is in O; ";
      continue;
    }
    ++outside;
    for (int i = 0; i < 4; ++i) ++outside_cells[&*c->vertex(i)];
  }
  if (outside != labels_.outside_count()) {
    problems << "|O| is " << outside << " but bookkeeping says " << labels_.outside_count() << "; ";
  }
  int64_t bad_counts = 0;
  for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end(); ++v) {
    const auto it = outside_cells.find(&*v);
    const int32_t expected = it == outside_cells.end() ? 0 : it->second;
    if (v->info().outside_cells != expected) ++bad_counts;
    if (v->info().cells != cells_around[&*v]) ++bad_counts;
    if (v->info().surface_faces != surface_faces[&*v]) ++bad_counts;
  }
  if (bad_counts > 0) problems << bad_counts << " vertices with a wrong count of cells in O; ";
  return problems.str();
}

// The exhaustive test on every vertex: the surface is a closed 2-manifold.
std::string DelaunayManifold::Impl::ValidateManifold() {
  int64_t irregular = 0;
  for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end(); ++v) {
    if (!regularity_.VertexRegular(v, Cell_handle())) ++irregular;
  }
  if (irregular == 0) return "";
  return std::to_string(irregular) + " vertices are not regular (surface not manifold); ";
}

// Every ray walked again from a freshly located camera, its crossings counted apart and
// compared with every cell's counts.
std::string DelaunayManifold::Impl::ValidateWeights() {
  std::unordered_map<const void*, std::array<int32_t, 5>> recount;  // crossings, spread[4]
  const auto count = [&](const Cell_handle& c, unsigned mask) {
    auto& entry = recount.try_emplace(&*c, std::array<int32_t, 5>{0, 0, 0, 0, 0}).first->second;
    ++entry[0];
    if (options_.w2_rule == W2Rule::kAllFaces) mask = 0xF;
    for (int k = 0; k < 4; ++k) entry[1 + k] += (mask >> k) & 1;
  };
  // Rays come camera by camera: each camera is located afresh once.
  int32_t located = -1;
  CameraStart start;
  ray_index_->ForEachInDirectionOrder([&](const RayRef& ray) {
    if (ray.camera != located) {
      start = walker_.Locate(ray.camera);
      located = ray.camera;
    }
    walker_.Walk(start, walker_.camera_point(ray.camera), vertex_of_point_[ray.point], count);
  });
  std::unordered_map<const void*, int32_t> behind;
  if (options_.behind_ratio > 0) {
    std::vector<Cell_handle> star;
    ray_index_->ForEachInDirectionOrder([&](const RayRef& ray) {
      const Cell_handle c = CellBehindRay(ray, &star);
      if (c != Cell_handle()) ++behind[&*c];
    });
  }
  int64_t wrong = 0;
  for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
    const auto it = recount.find(&*c);
    const std::array<int32_t, 5> expected =
        it == recount.end() ? std::array<int32_t, 5>{0, 0, 0, 0, 0} : it->second;
    const auto b = behind.find(&*c);
    bool same = c->info().crossings == expected[0] &&
                labels_.Behind(c) == (b == behind.end() ? 0 : b->second);
    for (int i = 0; i < 4; ++i) same &= labels_.Spread(c, i) == expected[1 + i];
    if (!same) ++wrong;
  }
  if (wrong == 0) return "";
  return std::to_string(wrong) + " cells whose ray count differs from a recount; ";
}

}  // namespace ms
