#include "mesh/visible_mesh.h"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <string>

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

VisibleMesh ExtractVisibleMesh(const Mesh& mesh, const View& view,
                               const VisibleMeshOptions& options) {
  options.Check();
  const int64_t num_vertices = static_cast<int64_t>(mesh.vertices.size());
  if (mesh.HasColors() && mesh.vertex_colors.size() != mesh.vertices.size()) {
    throw InputError("mesh: " + std::to_string(mesh.vertex_colors.size()) + " vertex colours for " +
                     std::to_string(num_vertices) + " vertices");
  }
  VisibleMesh out;
  std::vector<int32_t> remap(mesh.vertices.size(), -1);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    for (int32_t v : face) {
      if (v < 0 || v >= num_vertices) {
        throw InputError("mesh: face " + std::to_string(f) + " refers to vertex " +
                         std::to_string(v) + " of " + std::to_string(num_vertices));
      }
    }
    const Eigen::Vector3d& a = mesh.vertices[face[0]];
    const Eigen::Vector3d& b = mesh.vertices[face[1]];
    const Eigen::Vector3d& c = mesh.vertices[face[2]];
    if (!TriangleInFrustum(view, a, b, c, options.margin_px, options.near)) continue;
    if (!options.keep_back_facing && !TriangleFacesCamera(view, a, b, c)) continue;
    std::array<int32_t, 3> kept;
    for (int i = 0; i < 3; ++i) {
      int32_t& r = remap[face[i]];
      if (r < 0) {
        r = static_cast<int32_t>(out.mesh.vertices.size());
        out.mesh.vertices.push_back(mesh.vertices[face[i]]);
        if (mesh.HasColors()) out.mesh.vertex_colors.push_back(mesh.vertex_colors[face[i]]);
        out.vertex_ids.push_back(face[i]);
      }
      kept[i] = r;
    }
    out.mesh.faces.push_back(kept);
    out.face_ids.push_back(static_cast<int32_t>(f));
  }
  return out;
}

}  // namespace ms
