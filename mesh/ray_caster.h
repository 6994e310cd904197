// Ray casting against a triangle mesh on the CPU (the float-box tree of mesh/face_tree.h and
// Moller-Trumbore),
// for visibility of synthetic sparse points without a GPU and as a check independent of GL.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "mesh/face_tree.h"
#include "mesh/mesh.h"

namespace ms {

class RayCaster {
 public:
  // Keeps a copy of the triangles; degenerate faces never report hits.
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

  size_t num_faces() const { return triangles_.size(); }

 private:
  struct Triangle {
    Eigen::Vector3d a, e1, e2;  // a, b - a, c - a
    int32_t face;
  };
  // The nearest hit with t in (t_min, t_max), or with kAnyHit the first found.
  template <bool kAnyHit>
  bool Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                double t_max, Hit* hit) const;

  std::vector<Triangle> triangles_;
  std::vector<FloatBox3> boxes_;  // per triangle
  FaceTree tree_;                 // over the triangles (mesh/face_tree.h)
};

}  // namespace ms
