// Choosing the neighbour cameras of a camera for mesh sweeping (paper section 2.2): the nearest
// camera centres whose viewing directions differ from the camera's by less than a bound.
// Shared code: the coordinator calls it to build sweep jobs.
#pragma once

#include <vector>

#include "base/options.h"
#include "scene/scene.h"

namespace ms {

struct NeighbourOptions {
  static constexpr const char* kOptionGroup = "neighbours";
#define MS_OPTION_LIST "scene/neighbour_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

// Indices of up to `options.count` neighbours of view `camera`, nearest centre first. Ties in
// distance are broken by the smaller view index, so the result is deterministic. Throws
// InputError if `camera` is not a view of the scene.
std::vector<int> SelectNeighbours(const Scene& scene, int camera, const NeighbourOptions& options);
std::vector<int> SelectNeighbours(const Scene& scene, int camera, double max_angle_deg = 60,
                                  int count = 2);

}  // namespace ms
