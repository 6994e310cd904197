#include "scene/view_selection.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/error.h"

namespace ms {
namespace {

// A view at `center` whose optical axis is `axis` (any roll).
View ViewAt(const Eigen::Vector3d& center, const Eigen::Vector3d& axis) {
  View v;
  v.intrinsics = {64, 48, 50, 50, 32, 24};
  const Eigen::Vector3d z = axis.normalized();
  const Eigen::Vector3d helper =
      std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d y = z.cross(helper).normalized();
  const Eigen::Vector3d x = y.cross(z);
  v.R.row(0) = x.transpose();
  v.R.row(1) = y.transpose();
  v.R.row(2) = z.transpose();
  v.SetCenter(center);
  return v;
}

Eigen::Vector3d Direction(double degrees_from_z) {
  const double a = degrees_from_z * M_PI / 180;
  return {std::sin(a), 0, std::cos(a)};
}

TEST(SelectNeighbours, NearestFirstWithinTheAngleBound) {
  Scene scene;
  scene.views.push_back(ViewAt({0, 0, 0}, Direction(0)));
  scene.views.push_back(ViewAt({3, 0, 0}, Direction(10)));    // far, similar direction
  scene.views.push_back(ViewAt({1, 0, 0}, Direction(70)));    // near, too oblique
  scene.views.push_back(ViewAt({0, 2, 0}, Direction(-20)));   // middle
  scene.views.push_back(ViewAt({0, 0, 1.5}, Direction(59)));  // just inside 60
  EXPECT_EQ(SelectNeighbours(scene, 0), (std::vector<int>{4, 3}));
  EXPECT_EQ(SelectNeighbours(scene, 0, 60, 3), (std::vector<int>{4, 3, 1}));
  EXPECT_EQ(SelectNeighbours(scene, 0, 80, 2), (std::vector<int>{2, 4}));
  EXPECT_EQ(SelectNeighbours(scene, 0, 5, 2), (std::vector<int>{}));
  EXPECT_EQ(SelectNeighbours(scene, 0, 60, 0), (std::vector<int>{}));
}

TEST(SelectNeighbours, AngleBoundIsStrict) {
  Scene scene;
  scene.views.push_back(ViewAt({0, 0, 0}, Direction(0)));
  scene.views.push_back(ViewAt({1, 0, 0}, Direction(30)));
  scene.views.push_back(ViewAt({2, 0, 0}, Direction(29.9)));
  EXPECT_EQ(SelectNeighbours(scene, 0, 30, 2), (std::vector<int>{2}));
  EXPECT_EQ(SelectNeighbours(scene, 0, 30.2, 2), (std::vector<int>{1, 2}));
}

TEST(SelectNeighbours, SkipsCamerasAtTheSameCentre) {
  Scene scene;
  scene.views.push_back(ViewAt({1, 1, 1}, Direction(0)));
  scene.views.push_back(ViewAt({1, 1, 1}, Direction(5)));          // same centre (a rotation only)
  scene.views.push_back(ViewAt({1, 1, 1 + 1e-12}, Direction(0)));  // same centre up to noise
  scene.views.push_back(ViewAt({2, 1, 1}, Direction(0)));
  EXPECT_EQ(SelectNeighbours(scene, 0), (std::vector<int>{3}));
  EXPECT_EQ(SelectNeighbours(scene, 1), (std::vector<int>{3}));
  EXPECT_EQ(SelectNeighbours(scene, 3), (std::vector<int>{0, 1}));
}

TEST(SelectNeighbours, TiesGoToTheSmallerIndex) {
  Scene scene;
  scene.views.push_back(ViewAt({0, 0, 0}, Direction(0)));
  // Four cameras at exactly distance 1 (exact coordinates, so exactly equal distances).
  scene.views.push_back(ViewAt({0, -1, 0}, Direction(0)));
  scene.views.push_back(ViewAt({1, 0, 0}, Direction(0)));
  scene.views.push_back(ViewAt({-1, 0, 0}, Direction(0)));
  scene.views.push_back(ViewAt({0, 1, 0}, Direction(0)));
  EXPECT_EQ(SelectNeighbours(scene, 0), (std::vector<int>{1, 2}));
  EXPECT_EQ(SelectNeighbours(scene, 0, 60, 3), (std::vector<int>{1, 2, 3}));
  // From camera 2: camera 0 at 1, then cameras 1 and 4 both at sqrt(2), then camera 3 at 2.
  EXPECT_EQ(SelectNeighbours(scene, 2), (std::vector<int>{0, 1}));
  EXPECT_EQ(SelectNeighbours(scene, 2, 60, 3), (std::vector<int>{0, 1, 4}));
}

TEST(SelectNeighbours, BadArgumentsThrowInputError) {
  Scene scene;
  scene.source = "cams.nvm";
  scene.views.push_back(ViewAt({0, 0, 0}, Direction(0)));
  scene.views.push_back(ViewAt({1, 0, 0}, Direction(0)));
  try {
    SelectNeighbours(scene, 2);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cams.nvm: camera 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SelectNeighbours(scene, -1), InputError);
  EXPECT_THROW(SelectNeighbours(scene, 0, 0.0, 2), InputError);
  EXPECT_THROW(SelectNeighbours(scene, 0, 60, -1), InputError);
  EXPECT_EQ(SelectNeighbours(scene, 0, 180, 5), (std::vector<int>{1}));
}

}  // namespace
}  // namespace ms
