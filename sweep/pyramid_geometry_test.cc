#include "sweep/pyramid_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace ms {
namespace {

TEST(PyramidGeometry, CornersGoCounterClockwiseAroundTheBase) {
  const auto corners = PyramidBaseCorners();
  EXPECT_EQ(corners[0], Eigen::Vector3d(-1, -1, 0));
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d& a = corners[i];
    const Eigen::Vector3d& b = corners[(i + 1) % 4];
    EXPECT_EQ(a.z(), 0);
    EXPECT_EQ((b - a).norm(), 2);                    // a 2 x 2 square
    EXPECT_GT(a.cross(b).z(), 0) << "corner " << i;  // counter-clockwise seen from above
  }
}

TEST(PyramidGeometry, SidesFaceUpwardsWhereverTheApexIs) {
  for (const double apex_z : {kPyramidHeight, -kPyramidHeight}) {
    const Mesh sides = PyramidSides(apex_z);
    ASSERT_EQ(sides.vertices.size(), 5u);
    ASSERT_EQ(sides.faces.size(), 4u);
    EXPECT_EQ(sides.vertices[4], Eigen::Vector3d(0, 0, apex_z));
    for (size_t f = 0; f < sides.faces.size(); ++f) {
      EXPECT_GT(sides.FaceNormal(f).z(), 0) << "face " << f << ", apex at " << apex_z;
    }
    // No base facet: the four sides' area only.
    EXPECT_NEAR(sides.SurfaceArea(), 4 * std::sqrt(1 + apex_z * apex_z), 1e-12);
  }
}

TEST(PyramidGeometry, BaseSquareCoversTheBaseFacingUp) {
  const Mesh base = PyramidBaseSquare();
  ASSERT_EQ(base.faces.size(), 2u);
  EXPECT_DOUBLE_EQ(base.SurfaceArea(), 4);
  for (size_t f = 0; f < base.faces.size(); ++f) {
    EXPECT_EQ(base.FaceNormal(f), Eigen::Vector3d(0, 0, 1));
  }
}

}  // namespace
}  // namespace ms
