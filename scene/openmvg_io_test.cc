#include "scene/openmvg_io.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/error.h"
#include "scene/scene_io.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::DataPath;

std::string ErrorOf(const std::string& json) {
  try {
    ParseOpenMvg("sfm_data.json", json, nullptr);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(OpenMvgIo, FixtureWithPolymorphicIdsAndAnUnposedView) {
  const Scene scene = ReadScene(DataPath("openmvg/sfm_data.json"));
  ASSERT_EQ(scene.views.size(), 3u);  // d.png has no pose
  const Intrinsics& a = scene.views[0].intrinsics;
  EXPECT_EQ(scene.views[0].name, "a.png");
  EXPECT_EQ(a.fx, 50.5);
  EXPECT_EQ(a.fy, 50.5);
  EXPECT_EQ(a.cx, 32.25);
  EXPECT_EQ(a.cy, 23.75);
  EXPECT_EQ(a.k1, -0.1);
  EXPECT_EQ(a.k2, 0.02);
  EXPECT_EQ(a.k3, -0.003);
  // Intrinsic 1 names its type only by polymorphic_id 1 (pinhole_radial_k3, all zero).
  EXPECT_EQ(scene.views[1].intrinsics.fx, 52.0);
  EXPECT_FALSE(scene.views[1].intrinsics.HasDistortion());
  const Intrinsics& c = scene.views[2].intrinsics;  // pinhole_brown_t2
  EXPECT_EQ(c.width, 80);
  EXPECT_EQ(c.k1, -0.05);
  EXPECT_EQ(c.p1, 0.001);
  EXPECT_EQ(c.p2, -0.002);
  // Pose 1: centre at angle 60 degrees, radius 4, height 1.
  const Eigen::Vector3d centre(4 * std::cos(M_PI / 3), 4 * std::sin(M_PI / 3), 1);
  EXPECT_LT((scene.views[1].Center() - centre).norm(), 1e-14);
  EXPECT_LT((scene.views[1].R.row(2).transpose() + centre.normalized()).norm(), 1e-14);
  ASSERT_EQ(scene.points.size(), 3u);
  EXPECT_EQ(scene.points[0].position, Eigen::Vector3d(0.3, -0.2, 0.1));
  EXPECT_EQ(scene.points[0].color, (std::array<uint8_t, 3>{128, 128, 128}));
  // Observations of views 2, 0 and 3 (unposed, dropped), sorted by view.
  ASSERT_EQ(scene.points[1].observations.size(), 2u);
  EXPECT_EQ(scene.points[1].observations[0].view, 0);
  EXPECT_EQ(scene.points[1].observations[0].x, 11.0f);
  EXPECT_EQ(scene.points[1].observations[1].view, 2);
  EXPECT_EQ(scene.points[1].observations[1].x, 13.0f);
  EXPECT_EQ(scene.points[1].observations[1].y, 18.5f);
}

TEST(OpenMvgIo, ErrorsNameThePath) {
  EXPECT_EQ(ErrorOf("[1, 2"),
            "sfm_data.json: not valid JSON: [json.exception.parse_error.101] "
            "parse error at line 1, column 6: syntax error while parsing array - "
            "unexpected end of input; expected ']'");
  EXPECT_EQ(ErrorOf(R"({"views": [{"key": 0}]})"),
            "sfm_data.json: views[0]: missing field 'value'");
  EXPECT_EQ(ErrorOf(R"({"views": [], "intrinsics": [{"key": 0, "value": {"polymorphic_id": 3}}]})"),
            "sfm_data.json: intrinsics[0].value.polymorphic_id: id 3 names no earlier type");
  EXPECT_EQ(ErrorOf(R"({"views": [], "intrinsics": [], "extrinsics": [{"key": -1}]})"),
            "sfm_data.json: extrinsics[0].key: integer -1 is out of range [0, 4294967295]");
}

TEST(OpenMvgIo, UnsupportedCameraTypeIsNamed) {
  const std::string json = R"({"views": [{"key": 0, "value": {"polymorphic_id": 1073741824,
      "ptr_wrapper": {"id": 2147483649, "data": {"filename": "a.png", "width": 64, "height": 48,
      "id_view": 0, "id_intrinsic": 0, "id_pose": 0}}}}],
    "intrinsics": [{"key": 0, "value": {"polymorphic_id": 2147483649, "polymorphic_name": "fisheye",
      "ptr_wrapper": {"id": 2147483650, "data": {"width": 64, "height": 48, "focal_length": 10,
      "principal_point": [32, 24], "fisheye": [0, 0, 0, 0]}}}}],
    "extrinsics": [{"key": 0, "value": {"rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
      "center": [0, 0, 0]}}], "structure": []})";
  const std::string error = ErrorOf(json);
  EXPECT_NE(
      error.find("intrinsics[0].value.ptr_wrapper.data: camera type 'fisheye' is not supported"),
      std::string::npos)
      << error;
}

TEST(OpenMvgIo, RoundTrip) {
  testing::TempDir dir("openmvg_rt");
  Scene scene = testing::MakeSyntheticScene(dir.path().string());
  for (ScenePoint& p : scene.points) p.color = {128, 128, 128};  // sfm_data has no colours
  scene.views[1].intrinsics.k1 = -0.02;
  scene.views[2].intrinsics.p2 = 0.001;
  WriteOpenMvg(scene, dir / "sfm_data.json", {});
  testing::ExpectScenesNear(scene, ReadScene(dir / "sfm_data.json"), 1e-15);
  // Colours are a loss openMVG must report.
  scene.points[0].color = {1, 2, 3};
  EXPECT_THROW(WriteOpenMvg(scene, dir / "lossy.json", {}), InputError);
  SceneWriteOptions lossy;
  lossy.allow_lossy = true;
  WriteOpenMvg(scene, dir / "lossy.json", lossy);
  EXPECT_EQ(ReadScene(dir / "lossy.json").points[0].color, (std::array<uint8_t, 3>{128, 128, 128}));
}

TEST(OpenMvgIo, DeepNestingIsRejectedCheaply) {
  const std::string deep(1000000, '[');
  const std::string error = ErrorOf(deep);
  EXPECT_NE(error.find("sfm_data.json:"), std::string::npos) << error;
}

}  // namespace
}  // namespace ms
