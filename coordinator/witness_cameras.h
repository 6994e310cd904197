// The cameras that see a swept point besides the ones that matched it. A job's point lists C
// and the neighbours whose images matched it; another camera whose image holds the point, with
// no face of the iteration's closed mesh between, looks through the same free space. Its ray joins
// the point's, so that the insertion carves free space along every view of the point, not only
// the three that matched it: a surface left in front of a camera that matched nothing there
// (near its image border, say) is carved by the points the other cameras found behind it
// (docs/design/accuracy.md, "Witness rays"). The paper traces the matching cameras' rays only.
#pragma once

#include <cstdint>
#include <vector>

#include "manifold/delaunay_manifold.h"
#include "mesh/mesh.h"
#include "mesh/ray_caster.h"
#include "scene/scene.h"

namespace ms {

// Cameras whose rays a point of camera C can get: the nearest centres to C's, in any direction.
// Bounds the work per point on scenes of thousands of cameras.
constexpr int kWitnessCandidates = 32;
std::vector<std::vector<int>> WitnessCandidates(const Scene& scene);

class WitnessCameras {
 public:
  // `candidates`: WitnessCandidates(scene). `mesh`: the closed mesh the iteration's jobs were
  // cut from, the faces through Steiner points included (a point behind them is not known to
  // be seen). A face nearer the point than `relative_tolerance` times the camera's distance to
  // it does not hide it: the point was found near that surface. Keeps references to scene and
  // candidates, and a copy of the mesh's triangles.
  WitnessCameras(const Scene& scene, const std::vector<std::vector<int>>& candidates,
                 const Mesh& mesh, double relative_tolerance);

  // Appends to each point's cameras (the first is C, whose job found it) the candidates of C
  // that see it, in id order. Points are independent: the result does not depend on threads.
  // Returns how many cameras were added.
  int64_t Add(std::vector<RayPoint>* points) const;

 private:
  bool Sees(int camera, const Eigen::Vector3d& point) const;

  const Scene& scene_;
  const std::vector<std::vector<int>>& candidates_;
  RayCaster caster_;
  double relative_tolerance_;
};

}  // namespace ms
