#include "mesh/face_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "base/check.h"

namespace ms {
namespace {

// A face covering more cells than this is kept in the oversized list, which every query looks
// through: the closing faces of a reconstruction reach across the scene.
constexpr int64_t kMaxCellsPerFace = 512;
// Cell indices are packed into 21 bits each; a face beyond that is oversized.
constexpr int32_t kCellIndexLimit = (1 << 20) - 1;

// The box of face f grown by `grow`.
void GrownBox(const Mesh& mesh, int32_t f, double grow, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  const auto& t = mesh.faces[f];
  const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]],
                        &c = mesh.vertices[t[2]];
  *lo = a.cwiseMin(b).cwiseMin(c).array() - grow;
  *hi = a.cwiseMax(b).cwiseMax(c).array() + grow;
}

}  // namespace

FaceGrid::FaceGrid(const Mesh& mesh, double tolerance)
    // A little more than the tolerance, so that a box the check rounds outwards to floats is
    // inside ours.
    : tolerance_(tolerance * (1 + 1e-6) + 1e-12) {
  std::vector<double> sizes;
  sizes.reserve(mesh.faces.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    Eigen::Vector3d a, b;
    GrownBox(mesh, static_cast<int32_t>(f), 0, &a, &b);
    if (!a.allFinite() || !b.allFinite()) continue;
    sizes.push_back((b - a).maxCoeff());
    lo = lo.cwiseMin(a);
  }
  if (!sizes.empty()) {
    std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
    cell_ = 2 * sizes[sizes.size() / 2] + 2 * tolerance_;
    origin_ = lo;
  }
  if (!(cell_ > 0) || !std::isfinite(cell_)) cell_ = 1;
  placed_.reserve(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) Update(mesh, static_cast<int32_t>(f));
}

uint64_t FaceGrid::CellKey(int32_t x, int32_t y, int32_t z) {
  const auto bits = [](int32_t i) {
    return static_cast<uint64_t>(static_cast<uint32_t>(i + kCellIndexLimit + 1)) & 0x1fffff;
  };
  return bits(x) | bits(y) << 21 | bits(z) << 42;
}

FaceGrid::Place FaceGrid::PlaceOf(const Mesh& mesh, int32_t f) const {
  Place place;
  Eigen::Vector3d lo, hi;
  GrownBox(mesh, f, tolerance_, &lo, &hi);
  if (!lo.allFinite() || !hi.allFinite()) {
    place.oversized = true;
    return place;
  }
  int64_t cells = 1;
  for (int d = 0; d < 3; ++d) {
    const double from = std::floor((lo[d] - origin_[d]) / cell_);
    const double to = std::floor((hi[d] - origin_[d]) / cell_);
    if (!(from >= -kCellIndexLimit && to <= kCellIndexLimit)) {
      place.oversized = true;
      return place;
    }
    place.from[d] = static_cast<int32_t>(from);
    place.to[d] = static_cast<int32_t>(to);
    cells *= place.to[d] - place.from[d] + 1;
  }
  place.oversized = cells > kMaxCellsPerFace;
  return place;
}

void FaceGrid::Add(int32_t f, const Place& place) {
  if (place.oversized) {
    oversized_.insert(f);
    return;
  }
  for (int32_t x = place.from[0]; x <= place.to[0]; ++x) {
    for (int32_t y = place.from[1]; y <= place.to[1]; ++y) {
      for (int32_t z = place.from[2]; z <= place.to[2]; ++z) cells_[CellKey(x, y, z)].push_back(f);
    }
  }
}

void FaceGrid::Remove(int32_t f) {
  const Place& place = placed_[f];
  if (place.oversized) {
    oversized_.erase(f);
    return;
  }
  for (int32_t x = place.from[0]; x <= place.to[0]; ++x) {
    for (int32_t y = place.from[1]; y <= place.to[1]; ++y) {
      for (int32_t z = place.from[2]; z <= place.to[2]; ++z) {
        std::vector<int32_t>& faces = cells_[CellKey(x, y, z)];
        const auto it = std::find(faces.begin(), faces.end(), f);
        MS_CHECK(it != faces.end()) << "face grid: face " << f << " missing from its cell";
        *it = faces.back();
        faces.pop_back();
      }
    }
  }
}

void FaceGrid::Update(const Mesh& mesh, int32_t f) {
  MS_CHECK(f >= 0 && static_cast<size_t>(f) <= placed_.size() &&
           static_cast<size_t>(f) < mesh.faces.size())
      << "face grid: face " << f << " of " << placed_.size();
  if (static_cast<size_t>(f) == placed_.size()) {
    placed_.emplace_back();
  } else {
    Remove(f);
  }
  placed_[f] = PlaceOf(mesh, f);
  Add(f, placed_[f]);
}

void FaceGrid::Renumber(const std::vector<int64_t>& new_index) {
  MS_CHECK(new_index.size() == placed_.size())
      << "face grid: " << new_index.size() << " new indices for " << placed_.size() << " faces";
  for (auto& [key, faces] : cells_) {
    size_t kept = 0;
    for (int32_t f : faces) {
      if (new_index[f] >= 0) faces[kept++] = static_cast<int32_t>(new_index[f]);
    }
    faces.resize(kept);
  }
  std::unordered_set<int32_t> oversized;
  for (int32_t f : oversized_) {
    if (new_index[f] >= 0) oversized.insert(static_cast<int32_t>(new_index[f]));
  }
  oversized_ = std::move(oversized);
  std::vector<Place> placed;
  for (size_t f = 0; f < placed_.size(); ++f) {
    if (new_index[f] < 0) continue;
    MS_CHECK(new_index[f] == static_cast<int64_t>(placed.size()))
        << "face grid: renumbering must keep the faces' order";
    placed.push_back(placed_[f]);
  }
  placed_ = std::move(placed);
}

template <typename Visit>
void FaceGrid::ForEachNear(const Place& place, Visit&& visit) const {
  if (place.oversized) {  // every face
    for (size_t g = 0; g < placed_.size(); ++g) visit(static_cast<int32_t>(g));
    return;
  }
  for (int32_t x = place.from[0]; x <= place.to[0]; ++x) {
    for (int32_t y = place.from[1]; y <= place.to[1]; ++y) {
      for (int32_t z = place.from[2]; z <= place.to[2]; ++z) {
        const auto it = cells_.find(CellKey(x, y, z));
        if (it == cells_.end()) continue;
        for (int32_t g : it->second) visit(g);
      }
    }
  }
  for (int32_t g : oversized_) visit(g);
}

PairCandidates FaceGrid::Candidates(const Mesh& mesh, const std::vector<uint8_t>& focus) const {
  MS_CHECK(mesh.faces.size() == placed_.size() && focus.size() == placed_.size())
      << "face grid: " << placed_.size() << " faces held, " << mesh.faces.size() << " in the mesh, "
      << focus.size() << " focus flags";
  PairCandidates c;
  std::vector<Eigen::Vector3d> lo(2), hi(2);
  for (size_t fi = 0; fi < focus.size(); ++fi) {
    if (!focus[fi]) continue;
    const auto f = static_cast<int32_t>(fi);
    GrownBox(mesh, f, tolerance_, &lo[0], &hi[0]);
    ForEachNear(placed_[f], [&](int32_t g) {
      if (g == f) return;
      GrownBox(mesh, g, tolerance_, &lo[1], &hi[1]);
      // Grown boxes that meet, or any box that is not finite (the check decides about those).
      const bool meet =
          (lo[0].array() <= hi[1].array()).all() && (lo[1].array() <= hi[0].array()).all();
      const bool finite = lo[1].allFinite() && hi[1].allFinite() && lo[0].allFinite();
      if (meet || !finite) c.faces.push_back({std::min(f, g), std::max(f, g)});
    });
  }
  std::sort(c.faces.begin(), c.faces.end());
  c.faces.erase(std::unique(c.faces.begin(), c.faces.end()), c.faces.end());
  // Two vertices within the tolerance lie in faces whose grown boxes meet.
  const auto add_vertex_pairs = [&](const std::array<int32_t, 3>& a,
                                    const std::array<int32_t, 3>& b) {
    for (int32_t u : a) {
      for (int32_t v : b) {
        if (u != v) c.vertices.push_back({std::min(u, v), std::max(u, v)});
      }
    }
  };
  for (size_t f = 0; f < focus.size(); ++f) {
    if (focus[f]) add_vertex_pairs(mesh.faces[f], mesh.faces[f]);
  }
  for (const auto& [f, g] : c.faces) add_vertex_pairs(mesh.faces[f], mesh.faces[g]);
  std::sort(c.vertices.begin(), c.vertices.end());
  c.vertices.erase(std::unique(c.vertices.begin(), c.vertices.end()), c.vertices.end());
  return c;
}

}  // namespace ms
