// From a Scene (cameras, points, visibility) to what the Delaunay manifold consumes.
#pragma once

#include <vector>

#include "manifold/delaunay_manifold.h"
#include "scene/scene.h"

namespace ms {

// One ManifoldCamera per view: centre, rotation, and the normalised extent of its image.
std::vector<ManifoldCamera> ManifoldCamerasFromScene(const Scene& scene);

// One RayPoint per scene point: its position and the views that observe it.
std::vector<RayPoint> RayPointsFromScene(const Scene& scene);

}  // namespace ms
