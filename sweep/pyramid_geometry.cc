#include "sweep/pyramid_geometry.h"

namespace ms {

std::array<Eigen::Vector3d, 4> PyramidBaseCorners() {
  return {Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, -1, 0), Eigen::Vector3d(1, 1, 0),
          Eigen::Vector3d(-1, 1, 0)};
}

Mesh PyramidSides(double apex_z) {
  const std::array<Eigen::Vector3d, 4> corners = PyramidBaseCorners();
  Mesh mesh;
  mesh.vertices.assign(corners.begin(), corners.end());
  mesh.vertices.emplace_back(0, 0, apex_z);
  mesh.faces = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  return mesh;
}

Mesh PyramidBaseSquare() {
  const std::array<Eigen::Vector3d, 4> corners = PyramidBaseCorners();
  Mesh mesh;
  mesh.vertices.assign(corners.begin(), corners.end());
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

}  // namespace ms
