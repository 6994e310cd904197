// Ray casting against a triangle mesh on the CPU (the float-box tree of mesh/face_tree.h and
// Moller-Trumbore),
// for visibility of synthetic sparse points without a GPU and as a check independent of GL.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "mesh/face_tree.h"
#include "mesh/mesh.h"

namespace ms {

class RayCaster {
 public:
  // Keeps a copy of the vertices and of the faces' indices (about 60 bytes a face with the
  // tree); degenerate faces never report hits.
  explicit RayCaster(const Mesh& mesh);

  struct Hit {
    double t = 0;       // origin + t * direction
    int32_t face = -1;  // index into mesh.faces
  };
  // Nearest hit with t in (t_min, t_max); `direction` need not be unit length.
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                 double t_max, Hit* hit) const;
  // True if any triangle crosses the segment from `from` to `to`, ignoring the last `tolerance`
  // (scene units) before `to`, so a point lying on the surface does not occlude itself.
  bool Occluded(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double tolerance) const;

  size_t num_faces() const { return faces_.size(); }

 private:
  struct Face {
    std::array<int32_t, 3> vertices;
    int32_t face;  // index into the mesh's faces
  };
  struct Edges {
    Eigen::Vector3d e1, e2;  // b - a, c - a
  };
  Edges EdgesOf(const std::array<int32_t, 3>& face) const {
    const Eigen::Vector3d& a = vertices_[face[0]];
    return {vertices_[face[1]] - a, vertices_[face[2]] - a};
  }
  // The nearest hit with t in (t_min, t_max), or with kAnyHit the first found.
  template <bool kAnyHit>
  bool Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                double t_max, Hit* hit) const;

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Face> faces_;       // the faces that are not degenerate
  std::vector<FloatBox3> boxes_;  // per triangle
  FaceTree tree_;                 // over the triangles (mesh/face_tree.h)
};

}  // namespace ms
