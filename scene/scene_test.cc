#include "scene/scene.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace ms {
namespace {

View MakeView() {
  View v;
  v.name = "a.png";
  v.intrinsics = {640, 480, 500, 500, 320, 240};
  v.R = RotationFromQuaternion(0.9, 0.1, -0.2, 0.3);
  v.SetCenter({1, 2, -5});
  return v;
}

TEST(Camera, ProjectionAndRayAreInverse) {
  View v = MakeView();
  v.intrinsics.k1 = -0.1;
  v.intrinsics.k2 = 0.02;
  v.intrinsics.p1 = 0.001;
  const Eigen::Vector3d X(0.3, -0.2, 1.0);
  Eigen::Vector2d px;
  ASSERT_TRUE(v.Project(X, &px));
  const Eigen::Vector3d ray = v.PixelRay(px);
  const Eigen::Vector3d expected = (X - v.Center()).normalized();
  EXPECT_LT((ray - expected).norm(), 1e-9);
  EXPECT_NEAR(v.Center().x(), 1, 1e-12);
}

TEST(Camera, QuaternionRoundTrip) {
  const Eigen::Matrix3d R = RotationFromQuaternion(0.5, -0.5, 0.5, 0.5);
  const Eigen::Vector4d q = QuaternionFromRotation(R);
  EXPECT_LT((RotationFromQuaternion(q[0], q[1], q[2], q[3]) - R).norm(), 1e-12);
  EXPECT_TRUE(IsRotation(R));
  EXPECT_FALSE(IsRotation(2 * R));
}

TEST(Scene, ValidateNamesTheBadField) {
  Scene scene;
  scene.source = "model.nvm";
  scene.views.push_back(MakeView());
  scene.points.push_back({{0, 0, 1}, {{1, 2, 3}}, {{0, 1, 1}}});
  EXPECT_NO_THROW(scene.Validate());
  scene.points[0].observations.push_back({3, 0, 0});
  try {
    scene.Validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("model.nvm: point 0"), std::string::npos) << e.what();
  }
  scene.points[0].observations.pop_back();
  scene.views[0].t.x() = std::nan("");
  EXPECT_THROW(scene.Validate(), InputError);
}

// The model of a part of the images: the views kept, renumbered; the points at least two of them
// see, with only their observations.
TEST(Scene, SubsetOfViewsKeepsThePointsTwoKeptViewsSee) {
  Scene scene;
  scene.source = "model";
  for (int v = 0; v < 4; ++v) {
    scene.views.push_back(MakeView());
    scene.views.back().name = std::to_string(v) + ".png";
  }
  const auto point = [](std::vector<int32_t> views) {
    ScenePoint p;
    for (int32_t v : views) p.observations.push_back({v, 1.0f * v, 2.0f});
    return p;
  };
  scene.points = {point({0, 1, 3}), point({1, 2}), point({2, 3}), point({0, 2})};
  const Scene part = SubsetOfViews(scene, {1, 2, 3});
  ASSERT_EQ(part.views.size(), 3u);
  EXPECT_EQ(part.views[0].name, "1.png");
  ASSERT_EQ(part.points.size(), 3u);  // {0, 2}: one kept view only
  EXPECT_EQ(part.points[0].observations,
            (std::vector<Observation>{{0, 1.0f, 2.0f}, {2, 3.0f, 2.0f}}));
  EXPECT_EQ(part.points[1].observations.size(), 2u);
  EXPECT_NO_THROW(part.Validate());
  EXPECT_THROW(SubsetOfViews(scene, {2, 1}), InputError);
  EXPECT_THROW(SubsetOfViews(scene, {4}), InputError);
}

}  // namespace
}  // namespace ms
