// Test helpers for scene I/O (header-only, for *_test.cc files): scene comparison with a
// relative tolerance, fixture paths, and a small synthetic scene every format can hold
// (plus testing/testing.h's TempDir and ExpectInputError).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "scene/scene.h"
#include "testing/testing.h"  // TempDir, ExpectInputError

namespace ms::testing {

inline std::string DataPath(const std::string& relative) {
  return std::string(MS_SOURCE_DIR) + "/tests/data/" + relative;
}
inline std::string SharedData(const std::string& relative) {
  return std::string(MS_SHARED_DATA_DIR) + "/" + relative;
}
inline bool HaveSharedData() { return std::filesystem::is_directory(MS_SHARED_DATA_DIR); }

inline bool Near(double a, double b, double rel) {
  return std::abs(a - b) <= rel * std::max(1.0, std::max(std::abs(a), std::abs(b)));
}

// Cameras to `rel` relative error (1 for values below 1), names and sizes exact; points to `rel`,
// colours exact; observations: views exact, pixels within `pixel_tol` (0 = bit-exact floats).
inline void ExpectScenesNear(const Scene& a, const Scene& b, double rel, double pixel_tol = 0,
                             bool compare_names = true) {
  ASSERT_EQ(a.views.size(), b.views.size());
  for (size_t i = 0; i < a.views.size(); ++i) {
    SCOPED_TRACE("view " + std::to_string(i) + " " + a.views[i].name);
    const View& u = a.views[i];
    const View& v = b.views[i];
    if (compare_names) {
      EXPECT_EQ(u.name, v.name);
    }
    const Intrinsics& k = u.intrinsics;
    const Intrinsics& l = v.intrinsics;
    EXPECT_EQ(k.width, l.width);
    EXPECT_EQ(k.height, l.height);
    const double ka[] = {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3};
    const double la[] = {l.fx, l.fy, l.cx, l.cy, l.k1, l.k2, l.p1, l.p2, l.k3};
    for (int j = 0; j < 9; ++j)
      EXPECT_TRUE(Near(ka[j], la[j], rel)) << j << ": " << ka[j] << " vs " << la[j];
    EXPECT_LE((u.R - v.R).cwiseAbs().maxCoeff(), rel) << u.R << "\nvs\n" << v.R;
    for (int j = 0; j < 3; ++j)
      EXPECT_TRUE(Near(u.t[j], v.t[j], rel)) << u.t.transpose() << " vs " << v.t.transpose();
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    const ScenePoint& p = a.points[i];
    const ScenePoint& q = b.points[i];
    for (int j = 0; j < 3; ++j) EXPECT_TRUE(Near(p.position[j], q.position[j], rel));
    EXPECT_EQ(p.color, q.color);
    ASSERT_EQ(p.observations.size(), q.observations.size());
    for (size_t o = 0; o < p.observations.size(); ++o) {
      EXPECT_EQ(p.observations[o].view, q.observations[o].view);
      if (pixel_tol == 0) {
        EXPECT_EQ(p.observations[o].x, q.observations[o].x);
        EXPECT_EQ(p.observations[o].y, q.observations[o].y);
      } else {
        EXPECT_NEAR(p.observations[o].x, q.observations[o].x, pixel_tol);
        EXPECT_NEAR(p.observations[o].y, q.observations[o].y, pixel_tol);
      }
    }
  }
}

// Three views with fx = fy, principal point at the image centre and no distortion (so NVM,
// Bundler, COLMAP, openMVG hold it exactly), their images written as PNGs into `dir`, and
// points observed at their projections (as floats).
inline Scene MakeSyntheticScene(const std::string& dir) {
  Scene scene;
  scene.source = "synthetic";
  const int sizes[3][2] = {{40, 30}, {40, 30}, {48, 32}};
  const double focal[3] = {45.25, 50.0, 61.125};
  for (int i = 0; i < 3; ++i) {
    View v;
    v.name = "view" + std::to_string(i) + ".png";
    v.image_path = dir + "/" + v.name;
    cv::imwrite(v.image_path, cv::Mat(sizes[i][1], sizes[i][0], CV_8UC1, cv::Scalar(90 + i)));
    v.intrinsics.width = sizes[i][0];
    v.intrinsics.height = sizes[i][1];
    v.intrinsics.fx = v.intrinsics.fy = focal[i];
    v.intrinsics.cx = 0.5 * sizes[i][0];
    v.intrinsics.cy = 0.5 * sizes[i][1];
    const double angle = 0.7 * i + 0.1;
    const Eigen::Vector3d centre(3.7 * std::cos(angle), 3.7 * std::sin(angle), 0.3 * i + 0.2);
    const Eigen::Vector3d z = -centre.normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d y = z.cross(x);
    v.R.row(0) = x;
    v.R.row(1) = y;
    v.R.row(2) = z;
    v.SetCenter(centre);
    scene.views.push_back(v);
  }
  for (int p = 0; p < 7; ++p) {
    ScenePoint point;
    point.position = Eigen::Vector3d(0.1 * p - 0.3, 0.05 * p * p - 0.4, 0.3 - 0.07 * p) / 3.0;
    point.color = {static_cast<uint8_t>(30 * p), static_cast<uint8_t>(255 - 20 * p),
                   static_cast<uint8_t>(p * p)};
    for (int v = 0; v < 3; ++v) {
      if ((p + v) % 4 == 3) continue;  // not every point in every view
      Eigen::Vector2d px;
      if (scene.views[v].Project(point.position, &px)) {
        point.observations.push_back({v, static_cast<float>(px.x()), static_cast<float>(px.y())});
      }
    }
    scene.points.push_back(point);
  }
  return scene;
}

}  // namespace ms::testing
