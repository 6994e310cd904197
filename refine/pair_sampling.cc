#include "refine/pair_sampling.h"

#include <algorithm>
#include <vector>

namespace ms {

double RefineNearPlane(const Mesh& mesh, const View& view) {
  std::vector<double> z;
  z.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) {
    const double vz = view.ToCamera(v).z();
    if (vz > 0) z.push_back(vz);
  }
  if (z.empty()) return 1e-9;
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  return std::max(1e-9, 1e-3 * z[z.size() / 2]);
}

}  // namespace ms
