// Small closed meshes for the mesh checkers', the float cleanup's and the coordinator's tests.
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "mesh/mesh.h"

namespace ms::test_meshes {

using V = Eigen::Vector3d;

// Faces counter-clockwise seen from outside for a convex mesh around the origin.
void OrientOutward(Mesh* m);
Mesh Icosahedron();
// The octahedron |x| + |y| + |z| = radius, faces counter-clockwise seen from outside.
Mesh Octahedron(double radius);
Mesh Cube();
// A tetrahedron with its right-angled corner at `apex` and its other vertices at apex + s*e_i,
// s = +1 or -1 (outward faces either way).
Mesh Corner(const V& apex, double s);
Mesh Append(Mesh a, const Mesh& b);
// Two corners apex to apex, the second one pointing the other way with its apex at `apex`:
// exactly apart when the apex is outside the first one.
Mesh ApexToApex(const V& apex);
// Flips face f if its normal points towards `inside`.
void OrientAwayFrom(Mesh* m, size_t f, const V& inside);
// A closed bipyramid (two tetrahedra glued on the triangle 0 1 2) whose shared triangle has one
// edge of length `needle` (vertices 1 and 2): the faces 3 1 2 and 4 2 1 are needles.
Mesh Bipyramid(double needle);
// A rotation with no axis along the coordinate axes (Open3D's test scales each axis on its own,
// which makes axis-aligned near-coincidences look large to it).
Eigen::Matrix3d Rotation();

}  // namespace ms::test_meshes
