#include "mesh/visible_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "base/error.h"

namespace ms {

bool TriangleInFrustum(const View& view, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                       const Eigen::Vector3d& c, double margin_px, double near) {
  const Intrinsics& k = view.intrinsics;
  const std::array<Eigen::Vector3d, 3> p = {view.ToCamera(a), view.ToCamera(b), view.ToCamera(c)};
  // Half-spaces through the camera centre bounding the image rectangle [-m, W+m] x [-m, H+m]:
  // u = fx x/z + cx >= -m  <=>  fx x + (cx + m) z >= 0, and so on; plus z > near.
  const double m = margin_px;
  const auto all_outside = [&](auto inside) {
    return !inside(p[0]) && !inside(p[1]) && !inside(p[2]);
  };
  if (all_outside([&](const Eigen::Vector3d& q) { return q.z() > near; })) return false;
  if (all_outside([&](const Eigen::Vector3d& q) { return k.fx * q.x() + (k.cx + m) * q.z() >= 0; }))
    return false;
  if (all_outside([&](const Eigen::Vector3d& q) {
        return k.fx * q.x() + (k.cx - k.width - m) * q.z() <= 0;
      }))
    return false;
  if (all_outside([&](const Eigen::Vector3d& q) { return k.fy * q.y() + (k.cy + m) * q.z() >= 0; }))
    return false;
  if (all_outside([&](const Eigen::Vector3d& q) {
        return k.fy * q.y() + (k.cy - k.height - m) * q.z() <= 0;
      }))
    return false;
  return true;
}

bool TriangleFacesCamera(const View& view, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c) {
  const Eigen::Vector3d normal = (b - a).cross(c - a);
  const Eigen::Vector3d centroid = (a + b + c) / 3.0;
  return normal.dot(view.Center() - centroid) > 0;
}

namespace {

void CheckFaces(const Mesh& mesh) {
  const int64_t num_vertices = static_cast<int64_t>(mesh.vertices.size());
  if (mesh.HasColors() && mesh.vertex_colors.size() != mesh.vertices.size()) {
    throw InputError("mesh: " + std::to_string(mesh.vertex_colors.size()) + " vertex colours for " +
                     std::to_string(num_vertices) + " vertices");
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int32_t v : mesh.faces[f]) {
      if (v < 0 || v >= num_vertices) {
        throw InputError("mesh: face " + std::to_string(f) + " refers to vertex " +
                         std::to_string(v) + " of " + std::to_string(num_vertices));
      }
    }
  }
}

bool Kept(const Mesh& mesh, size_t f, const View& view, const VisibleMeshOptions& options) {
  const auto& face = mesh.faces[f];
  const Eigen::Vector3d& a = mesh.vertices[face[0]];
  const Eigen::Vector3d& b = mesh.vertices[face[1]];
  const Eigen::Vector3d& c = mesh.vertices[face[2]];
  if (!TriangleInFrustum(view, a, b, c, options.margin_px, options.near)) return false;
  return options.keep_back_facing || TriangleFacesCamera(view, a, b, c);
}

// The compact mesh of `faces` (ascending): vertices numbered in order of first use. `remap` is
// all -1 for every vertex of `mesh` on entry and is left so.
VisibleMesh Assemble(const Mesh& mesh, const std::vector<int32_t>& faces,
                     std::vector<int32_t>* remap) {
  VisibleMesh out;
  out.face_ids = faces;
  out.mesh.faces.reserve(faces.size());
  for (int32_t f : faces) {
    std::array<int32_t, 3> kept;
    for (int i = 0; i < 3; ++i) {
      const int32_t v = mesh.faces[f][i];
      int32_t& r = (*remap)[v];
      if (r < 0) {
        r = static_cast<int32_t>(out.mesh.vertices.size());
        out.mesh.vertices.push_back(mesh.vertices[v]);
        if (mesh.HasColors()) out.mesh.vertex_colors.push_back(mesh.vertex_colors[v]);
        out.vertex_ids.push_back(v);
      }
      kept[i] = r;
    }
    out.mesh.faces.push_back(kept);
  }
  for (int32_t v : out.vertex_ids) (*remap)[v] = -1;
  return out;
}

// Interleaves the low 21 bits of x, y and z (a Morton code: nearby cells, nearby codes).
uint64_t Morton(uint32_t x, uint32_t y, uint32_t z) {
  const auto spread = [](uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

constexpr int32_t kFacesPerBlock = 32;

}  // namespace

VisibleMesh ExtractVisibleMesh(const Mesh& mesh, const View& view,
                               const VisibleMeshOptions& options) {
  options.Check();
  CheckFaces(mesh);
  std::vector<int32_t> faces;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (Kept(mesh, f, view, options)) faces.push_back(static_cast<int32_t>(f));
  }
  std::vector<int32_t> remap(mesh.vertices.size(), -1);
  return Assemble(mesh, faces, &remap);
}

VisibleMeshIndex::VisibleMeshIndex(const Mesh& mesh) : mesh_(mesh) {
  CheckFaces(mesh);
  if (mesh.faces.empty()) return;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& face : mesh.faces) {
    for (int32_t v : face) {
      lo = lo.cwiseMin(mesh.vertices[v]);
      hi = hi.cwiseMax(mesh.vertices[v]);
    }
  }
  const Eigen::Vector3d extent = (hi - lo).cwiseMax(1e-300);
  std::vector<std::pair<uint64_t, int32_t>> keyed(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    const Eigen::Vector3d centroid =
        (mesh.vertices[face[0]] + mesh.vertices[face[1]] + mesh.vertices[face[2]]) / 3.0;
    const Eigen::Vector3d cell =
        ((centroid - lo).cwiseQuotient(extent) * 2097151.0).cwiseMax(0.0).cwiseMin(2097151.0);
    keyed[f] = {Morton(static_cast<uint32_t>(cell.x()), static_cast<uint32_t>(cell.y()),
                       static_cast<uint32_t>(cell.z())),
                static_cast<int32_t>(f)};
  }
  std::sort(keyed.begin(), keyed.end());
  order_.reserve(keyed.size());
  for (const auto& [code, f] : keyed) order_.push_back(f);
  // Rounding in the plane tests is ~1e-16 of the coordinates; the boxes grow by far more.
  const double widen = 1e-9 * ((hi - lo).norm() + lo.cwiseAbs().cwiseMax(hi.cwiseAbs()).norm());
  for (int32_t begin = 0; begin < static_cast<int32_t>(order_.size()); begin += kFacesPerBlock) {
    Block block;
    block.begin = begin;
    block.end = std::min<int32_t>(begin + kFacesPerBlock, static_cast<int32_t>(order_.size()));
    Eigen::Vector3d b_lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d b_hi = -b_lo;
    for (int32_t i = block.begin; i < block.end; ++i) {
      for (int32_t v : mesh.faces[order_[i]]) {
        b_lo = b_lo.cwiseMin(mesh.vertices[v]);
        b_hi = b_hi.cwiseMax(mesh.vertices[v]);
      }
    }
    block.centre = (b_lo + b_hi) / 2;
    block.half = (b_hi - b_lo) / 2 + Eigen::Vector3d::Constant(widen);
    blocks_.push_back(block);
  }
}

VisibleMesh VisibleMeshIndex::Extract(const View& view, const VisibleMeshOptions& options) const {
  options.Check();
  const Intrinsics& k = view.intrinsics;
  const double m = options.margin_px;
  // TriangleInFrustum's half-spaces as linear functions of camera coordinates q = R x + t:
  // a face is out when all its vertices have a.q + offset on the outer side of the plane.
  struct Plane {
    Eigen::Vector3d a;
    double offset;
    bool inside_is_positive;
  };
  const Plane planes[5] = {{{0, 0, 1}, -options.near, true},
                           {{k.fx, 0, k.cx + m}, 0, true},
                           {{k.fx, 0, k.cx - k.width - m}, 0, false},
                           {{0, k.fy, k.cy + m}, 0, true},
                           {{0, k.fy, k.cy - k.height - m}, 0, false}};
  // In world coordinates: g.x + h, with g = R^T a, h = a.t + offset.
  Eigen::Vector3d g[5];
  double h[5];
  for (int p = 0; p < 5; ++p) {
    g[p] = view.R.transpose() * planes[p].a;
    h[p] = planes[p].a.dot(view.t) + planes[p].offset;
  }
  std::vector<int32_t> faces;
  for (const Block& block : blocks_) {
    bool out = false;
    for (int p = 0; p < 5 && !out; ++p) {
      const double at_centre = g[p].dot(block.centre) + h[p];
      const double reach = g[p].cwiseAbs().dot(block.half);
      out = planes[p].inside_is_positive ? at_centre + reach < 0 : at_centre - reach > 0;
    }
    if (out) continue;
    for (int32_t i = block.begin; i < block.end; ++i) {
      if (Kept(mesh_, order_[i], view, options)) faces.push_back(order_[i]);
    }
  }
  std::sort(faces.begin(), faces.end());
  thread_local std::vector<int32_t> remap;
  if (remap.size() < mesh_.vertices.size()) remap.assign(mesh_.vertices.size(), -1);
  return Assemble(mesh_, faces, &remap);
}

}  // namespace ms
