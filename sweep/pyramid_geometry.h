// The paper's synthetic pyramid (section 3.1): a square base [-1, 1]^2 at z = 0 and an apex
// above (or below) its centre, 0.3 away. The one definition of its geometry for both pyramid
// scenes: `manisweep synth pyramid-up / pyramid-down` (tools/synth_scenes.h; also the embedded
// default scene of `manisweep reconstruct`) and the sweep's test scene
// (testing/sweep_test_scene.h). Production code; no GL.
#pragma once

#include <Eigen/Core>
#include <array>

#include "mesh/mesh.h"

namespace ms {

// The apex's distance from the base plane (the paper's 0.3 m).
inline constexpr double kPyramidHeight = 0.3;

// The base's corners, counter-clockwise seen from above (z > 0), from (-1, -1, 0).
std::array<Eigen::Vector3d, 4> PyramidBaseCorners();

// The four sides without the base: the corners (vertices 0-3), then the apex (0, 0, apex_z)
// (vertex 4); face i is corner i, corner i + 1, apex: counter-clockwise seen from above.
Mesh PyramidSides(double apex_z);

// The paper's initial manifold for the pyramids: the base square (2 triangles) at z = 0,
// counter-clockwise seen from above.
Mesh PyramidBaseSquare();

}  // namespace ms
