#include "tools/render.h"

#include <gtest/gtest.h>

#include "scene/camera.h"

namespace ms {
namespace {

View Camera() {
  View view;
  view.intrinsics = {64, 48, 60, 60, 32, 24};
  view.SetCenter({0, 0, -3});  // looks down +z at the origin
  return view;
}

Mesh Square(bool facing_camera) {
  Mesh mesh;
  mesh.vertices = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  // Counter-clockwise seen from the camera (at -z) = normal towards -z.
  if (facing_camera) {
    mesh.faces = {{0, 2, 1}, {0, 3, 2}};
  } else {
    mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  }
  return mesh;
}

TEST(RenderShaded, LitFrontFacesAndRedBackFaces) {
  const gl::GlContext gl;
  const cv::Mat front = RenderShaded(gl, Square(true), Camera());
  const cv::Mat back = RenderShaded(gl, Square(false), Camera());
  ASSERT_EQ(front.size(), cv::Size(64, 48));
  const cv::Vec3b centre_front = front.at<cv::Vec3b>(24, 32);
  const cv::Vec3b centre_back = back.at<cv::Vec3b>(24, 32);
  EXPECT_GT(centre_front[0], 200);  // head-on, lit from the camera: nearly white
  EXPECT_EQ(centre_front[0], centre_front[2]);
  EXPECT_GT(centre_back[2], 2 * centre_back[0]);  // seen from behind: red
  // The square covers |x| < 1 at depth 3 with f = 60: pixels 12..52; outside is background.
  EXPECT_EQ(front.at<cv::Vec3b>(2, 2), cv::Vec3b(40, 34, 30));
}

TEST(RenderShaded, ScalesLargeViewsExactly) {
  View view = Camera();
  view.intrinsics = {3072, 2048, 2759.48, 2764.16, 1520.69, 1006.81};
  const View scaled = ScaledView(view, 1536);
  EXPECT_EQ(scaled.intrinsics.width, 1536);
  EXPECT_EQ(scaled.intrinsics.height, 1024);
  EXPECT_DOUBLE_EQ(scaled.intrinsics.cx, 1520.69 / 2);
  EXPECT_DOUBLE_EQ(scaled.intrinsics.fy, 2764.16 / 2);
  EXPECT_EQ(ScaledView(view, 0).intrinsics.width, 3072);
}

}  // namespace
}  // namespace ms
