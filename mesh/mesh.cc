#include "mesh/mesh.h"

#include <Eigen/Geometry>

namespace ms {

Eigen::Vector3d Mesh::FaceNormal(size_t f) const {
  const auto& t = faces[f];
  const Eigen::Vector3d n =
      (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

double Mesh::FaceArea(size_t f) const {
  const auto& t = faces[f];
  return 0.5 * (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
}

double Mesh::SurfaceArea() const {
  double area = 0;
  for (size_t f = 0; f < faces.size(); ++f) area += FaceArea(f);
  return area;
}

void Mesh::RemoveUnreferencedVertices() {
  std::vector<int32_t> remap(vertices.size(), -1);
  std::vector<Eigen::Vector3d> kept;
  std::vector<std::array<uint8_t, 3>> kept_colors;
  for (auto& face : faces) {
    for (int32_t& v : face) {
      if (remap[v] < 0) {
        remap[v] = static_cast<int32_t>(kept.size());
        kept.push_back(vertices[v]);
        if (HasColors()) kept_colors.push_back(vertex_colors[v]);
      }
      v = remap[v];
    }
  }
  vertices = std::move(kept);
  vertex_colors = std::move(kept_colors);
}

Mesh FacesWithoutFlaggedVertices(const Mesh& mesh, const std::vector<uint8_t>& flagged) {
  Mesh out;
  out.vertices = mesh.vertices;
  out.vertex_colors = mesh.vertex_colors;
  for (const auto& f : mesh.faces) {
    if (!flagged[f[0]] && !flagged[f[1]] && !flagged[f[2]]) out.faces.push_back(f);
  }
  out.RemoveUnreferencedVertices();
  return out;
}

}  // namespace ms
