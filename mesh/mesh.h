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
// vertices removed. Cut from a closed 2-manifold, that is a 2-manifold with boundary except
// where a vertex keeps faces on two sides of dropped ones (a bow-tie, which check-mesh and
// Open3D call non-manifold); KeepOneFanPerVertex mends those.
Mesh FacesWithoutFlaggedVertices(const Mesh& mesh, const std::vector<uint8_t>& flagged);

// Removes faces until around every vertex the faces form one fan (each joined to the next through
// an edge at the vertex): at a vertex with several, the fan of most faces stays (ties: the one
// with the smallest face index), repeated until none is left, since removing a fan may split
// another vertex's. Unreferenced vertices are removed. Returns the faces removed.
int64_t KeepOneFanPerVertex(Mesh* mesh);

// A point cloud with optional normals and colours (what sweeping finds, what synth samples).
struct PointCloud {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;        // empty, or one per point
  std::vector<std::array<uint8_t, 3>> colors;  // empty, or one per point
  std::vector<float> scalars;                  // empty, or one per point (e.g. NCC)
};

}  // namespace ms
