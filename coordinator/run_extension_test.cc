// The scene of an extension: the run's views kept in place, the model's new views and the points
// they see appended, old cameras checked against the run's.
#include "coordinator/run_extension.h"

#include <gtest/gtest.h>

#include "testing/testing.h"

namespace ms {
namespace {

View ViewAt(const std::string& name, double x) {
  View v;
  v.name = name;
  v.intrinsics = {64, 48, 50, 50, 32, 24};
  v.SetCenter({x, 0, -5});
  return v;
}

ScenePoint PointSeenBy(std::vector<int32_t> views, double x) {
  ScenePoint p;
  p.position = Eigen::Vector3d(x, 0, 0);
  for (int32_t v : views) p.observations.push_back({v, 1.0f, 2.0f});
  return p;
}

// The run: views a and b. The model: c first, then b and a, so its indices differ from the run's.
struct Fixture {
  Scene run, model;
  Fixture() {
    run.views = {ViewAt("a.png", 0), ViewAt("b.png", 1)};
    run.points = {PointSeenBy({0, 1}, 0.5)};
    model.views = {ViewAt("c.png", 2), ViewAt("b.png", 1), ViewAt("a.png", 0)};
    model.points = {PointSeenBy({1, 2}, 0.5),      // old views only: not appended
                    PointSeenBy({0, 1}, 1.5),      // c and b
                    PointSeenBy({0, 1, 2}, 1.0)};  // c, b and a
  }
};

TEST(ExtendScene, AppendsTheNewViewsAndThePointsTheySee) {
  const Fixture f;
  const ExtendedScene out = ExtendScene(f.run, f.model, "model", ExtendOptions{});
  ASSERT_EQ(out.scene.views.size(), 3u);
  EXPECT_EQ(out.scene.views[0].name, "a.png");
  EXPECT_EQ(out.scene.views[2].name, "c.png");
  ASSERT_EQ(out.scene.points.size(), 3u);
  EXPECT_EQ(out.scene.points[0].position, f.run.points[0].position);  // the run's, unchanged
  // Renumbered into the extended scene (c is view 2) and sorted by view.
  EXPECT_EQ(out.scene.points[1].observations[0].view, 1);
  EXPECT_EQ(out.scene.points[1].observations[1].view, 2);
  EXPECT_EQ(out.scene.points[2].observations.size(), 3u);
  EXPECT_EQ(out.scene.points[2].observations[0].view, 0);
  EXPECT_NO_THROW(out.scene.Validate());
  EXPECT_EQ(out.extension.views_before, 2);
  EXPECT_EQ(out.extension.views_after, 3);
  EXPECT_EQ(out.extension.points_before, 1);
  EXPECT_EQ(out.extension.points_after, 3);
  const std::vector<RayPoint> batch = ExtensionBatch(out.scene, out.extension);
  ASSERT_EQ(batch.size(), 2u);
  EXPECT_EQ(batch[1].cameras, (std::vector<int32_t>{0, 1, 2}));
}

// The new cameras, their neighbours, and the old cameras that see the new region at least half as
// much as what they were reconstructed from.
TEST(ExtendScene, SweepsTheNewCamerasAndTheOldOnesThatLookIntoTheirRegion) {
  Scene scene;
  for (int v = 0; v < 5; ++v) scene.views.push_back(ViewAt(std::to_string(v) + ".png", v));
  // The run: views 0-2, points 0-3. The extension: views 3 and 4, points 4-6.
  scene.points = {PointSeenBy({0, 1}, 0), PointSeenBy({0, 1}, 0), PointSeenBy({1, 2}, 0),
                  PointSeenBy({1, 2}, 0), PointSeenBy({2, 3}, 0), PointSeenBy({1, 3, 4}, 0),
                  PointSeenBy({3, 4}, 0)};
  RunExtension e;
  e.views_before = 3;
  e.views_after = 5;
  e.points_before = 4;
  e.points_after = 7;
  // View 3's neighbour is 4, view 4's is 3: no old camera by position.
  const std::vector<std::vector<int>> neighbours = {{1}, {0}, {1}, {4}, {3}};
  // View 2: 1 shared of 2 before (0.5, swept); view 1: 1 of 4 (0.25); view 0: none.
  EXPECT_EQ(ExtensionSweptCameras(scene, e, neighbours), (std::vector<uint8_t>{0, 0, 1, 1, 1}));
  const std::vector<std::vector<int>> near_old = {{1}, {0}, {1}, {0}, {3}};
  EXPECT_EQ(ExtensionSweptCameras(scene, e, near_old), (std::vector<uint8_t>{1, 0, 1, 1, 1}));
}

TEST(ExtendScene, RefusesMovedTurnedMissingAndNothingNew) {
  const ExtendOptions options;
  Fixture moved;
  moved.model.views[1].SetCenter({1.2, 0, -5});  // b, by 0.2 of a viewing distance near 5
  testing::ExpectInputError([&] { ExtendScene(moved.run, moved.model, "m.txt", options); },
                            {"m.txt", "camera 1 (b.png) moved by 0.2", "max-camera-shift"});
  Fixture turned;
  const Eigen::Vector3d c = turned.model.views[2].Center();
  turned.model.views[2].R = RotationFromQuaternion(0.9996, 0.0, 0.0279, 0.0);  // 3.2 degrees
  turned.model.views[2].SetCenter(c);
  testing::ExpectInputError([&] { ExtendScene(turned.run, turned.model, "m.txt", options); },
                            {"camera 0 (a.png)", "turned by 3.2"});
  Fixture missing;
  missing.model.views[2].name = "d.png";
  testing::ExpectInputError([&] { ExtendScene(missing.run, missing.model, "m.txt", options); },
                            {"image a.png of the run (camera 0) is not in the model"});
  Fixture same;
  same.model = same.run;
  testing::ExpectInputError([&] { ExtendScene(same.run, same.model, "m.txt", options); },
                            {"no new image"});
}

}  // namespace
}  // namespace ms
