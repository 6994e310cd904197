// Choosing the neighbour cameras of a camera for mesh sweeping (paper section 2.2): the nearest
// camera centres whose viewing directions differ from the camera's by less than a bound.
// Shared code: the coordinator calls it to build sweep jobs.
#pragma once

#include <vector>

#include "scene/scene.h"

namespace ms {

struct NeighbourOptions {
  // Keep only cameras whose optical axes differ from the camera's by strictly less than this.
  double max_angle_deg = 60;
  // How many neighbours to return (fewer when fewer qualify).
  int count = 2;
  // Cameras closer than this fraction of the camera-centre bounding-box diagonal count as "at
  // the same centre" (no parallax, useless for stereo) and are skipped.
  double same_center_fraction = 1e-6;
  void Check() const;  // throws InputError naming the field
};

// Indices of up to `options.count` neighbours of view `camera`, nearest centre first. Ties in
// distance are broken by the smaller view index, so the result is deterministic. Throws
// InputError if `camera` is not a view of the scene.
std::vector<int> SelectNeighbours(const Scene& scene, int camera, const NeighbourOptions& options);
std::vector<int> SelectNeighbours(const Scene& scene, int camera, double max_angle_deg = 60,
                                  int count = 2);

}  // namespace ms
