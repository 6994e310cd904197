// Ray casting against a triangle mesh on the CPU (bounding-volume hierarchy + Moller-Trumbore),
// for visibility of synthetic sparse points without a GPU and as a check independent of GL.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

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
  struct Node {
    Eigen::Vector3d min, max;
    int32_t first = 0;  // leaf: first triangle; inner: index of the left child
    int32_t right = 0;  // inner: index of the right child
    int32_t count = 0;  // leaf: triangle count (> 0); inner: 0
  };
  int32_t Build(int32_t first, int32_t count, int depth);
  template <bool kAnyHit>
  bool Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                double t_max, Hit* hit) const;

  std::vector<Triangle> triangles_;
  std::vector<Node> nodes_;
};

}  // namespace ms
