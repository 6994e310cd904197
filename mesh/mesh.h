// Triangle mesh as the project passes it around and writes it.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace ms {

struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int32_t, 3>> faces;          // counter-clockwise seen from outside
  std::vector<std::array<uint8_t, 3>> vertex_colors;  // empty, or one per vertex

  size_t NumVertices() const { return vertices.size(); }
  size_t NumFaces() const { return faces.size(); }
  bool HasColors() const { return !vertex_colors.empty(); }
  // Unit normal of face f (zero for a degenerate face).
  Eigen::Vector3d FaceNormal(size_t f) const;
  double FaceArea(size_t f) const;
  double SurfaceArea() const;
  // Removes vertices no face uses, renumbering faces.
  void RemoveUnreferencedVertices();
};

// The faces of `mesh` none of whose vertices is flagged (one flag per vertex), unreferenced
// vertices removed.
Mesh FacesWithoutFlaggedVertices(const Mesh& mesh, const std::vector<uint8_t>& flagged);

// A point cloud with optional normals and colours (what sweeping finds, what synth samples).
struct PointCloud {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;        // empty, or one per point
  std::vector<std::array<uint8_t, 3>> colors;  // empty, or one per point
  std::vector<float> scalars;                  // empty, or one per point (e.g. NCC)
};

}  // namespace ms
