#include "tools/synth.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "base/log.h"
#include "gl/mesh_renderer.h"
#include "testing/gl_testing.h"
#include "tools/synth_scenes.h"

namespace ms {
namespace {

class SynthTest : public gl::SharedGlContextTest {};

SynthOptions Small(const std::string& scene, int views = 4) {
  SynthOptions o;
  o.scene = scene;
  o.views = views;
  o.width = 160;
  o.height = 120;
  o.supersampling = 1;
  return o;
}

double SignedVolume(const Mesh& mesh) {
  double volume = 0;
  for (const auto& f : mesh.faces) {
    volume += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]])) / 6;
  }
  return volume;
}

TEST(SynthOptions, ChecksFields) {
  SynthOptions o;
  o.scene = "castle";
  EXPECT_THROW(o.Check(), InputError);
  o = SynthOptions{};
  o.views = 1;
  EXPECT_THROW(o.Check(), InputError);
  o = SynthOptions{};
  o.image_noise = -1;
  EXPECT_THROW(o.Check(), InputError);
  o = SynthOptions{};
  o.supersampling = 0;
  EXPECT_THROW(o.Check(), InputError);
  EXPECT_NO_THROW(SynthOptions{}.Check());
}

TEST(SynthScenes, PyramidsAreThePapers) {
  for (bool up : {false, true}) {
    const SynthGeometry g = MakePyramidScene(up, {16, 800, 600, 1});
    ASSERT_EQ(g.mesh.faces.size(), 4u);  // no base facet
    EXPECT_NEAR(g.mesh.SurfaceArea(), 4 * 0.5 * 2 * std::hypot(1.0, 0.3), 1e-12);
    double apex_z = 0;
    for (const Eigen::Vector3d& v : g.mesh.vertices) {
      if (v.head<2>().norm() < 1e-12) apex_z = v.z();
    }
    EXPECT_DOUBLE_EQ(apex_z, up ? 0.3 : -0.3);
    for (size_t f = 0; f < g.mesh.faces.size(); ++f) {
      EXPECT_GT(g.mesh.FaceNormal(f).z(), 0) << "faces must face the cameras (above)";
    }
    EXPECT_EQ(g.initial_mesh.faces.size(), 2u);
    EXPECT_NEAR(g.initial_mesh.SurfaceArea(), 4, 1e-12);
    ASSERT_EQ(g.views.size(), 16u);
    for (const View& v : g.views) {
      EXPECT_GT(v.Center().z(), 1.0);
      EXPECT_TRUE(IsRotation(v.R));
    }
  }
}

TEST(SynthScenes, BlobIsClosedAndOutwardFacing) {
  const SynthGeometry g = MakeBlobScene({8, 160, 120, 3});
  EXPECT_EQ(g.mesh.faces.size(), 20480u);
  EXPECT_GT(SignedVolume(g.mesh), 3.0);  // ~4/3 pi for radius ~1
  std::map<std::pair<int32_t, int32_t>, int> edges;
  for (const auto& f : g.mesh.faces) {
    for (int k = 0; k < 3; ++k) ++edges[{f[k], f[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : edges) {
    ASSERT_EQ(count, 1);
    ASSERT_EQ(edges.count({edge.second, edge.first}), 1u) << "boundary edge";
  }
  // Another seed, another shape.
  const SynthGeometry other = MakeBlobScene({8, 160, 120, 4});
  EXPECT_GT((other.mesh.vertices[100] - g.mesh.vertices[100]).norm(), 1e-6);
}

TEST_F(SynthTest, PyramidDatasetHasTheFourCornersSeenByEveryView) {
  SynthOptions o = Small("pyramid-up", 6);
  const SynthDataset d = MakeSynthDataset(o, context_);
  EXPECT_EQ(d.scene_name, "pyramid-up");
  ASSERT_EQ(d.scene.points.size(), 4u);
  for (const ScenePoint& p : d.scene.points) {
    EXPECT_NEAR(std::abs(p.position.x()), 1, 1e-12);
    EXPECT_NEAR(std::abs(p.position.y()), 1, 1e-12);
    EXPECT_EQ(p.position.z(), 0);
    ASSERT_EQ(p.observations.size(), 6u);
    for (const Observation& ob : p.observations) {
      Eigen::Vector2d pixel;
      ASSERT_TRUE(d.scene.views[ob.view].Project(p.position, &pixel));
      EXPECT_NEAR(pixel.x(), ob.x, 1e-3);
      EXPECT_NEAR(pixel.y(), ob.y, 1e-3);
    }
  }
  ASSERT_EQ(d.images.size(), 6u);
  EXPECT_EQ(d.images[0].size(), cv::Size(160, 120));
  EXPECT_EQ(d.images[0].type(), CV_8UC3);
  EXPECT_EQ(d.initial_mesh.faces.size(), 2u);
  EXPECT_NO_THROW(d.scene.Validate());
}

TEST_F(SynthTest, SameSeedSameDatasetOtherSeedOtherTexture) {
  SynthOptions o = Small("blob", 4);
  o.points = 200;
  o.image_noise = 3;
  o.point_noise = 0.01;
  const SynthDataset a = MakeSynthDataset(o, context_);
  const SynthDataset b = MakeSynthDataset(o, context_);
  ASSERT_EQ(a.images.size(), 4u);
  for (size_t i = 0; i < a.images.size(); ++i) {
    EXPECT_EQ(cv::norm(a.images[i], b.images[i], cv::NORM_INF), 0) << "view " << i;
  }
  ASSERT_EQ(a.scene.points.size(), b.scene.points.size());
  for (size_t i = 0; i < a.scene.points.size(); ++i) {
    EXPECT_EQ(a.scene.points[i].position, b.scene.points[i].position);
    EXPECT_EQ(a.scene.points[i].observations, b.scene.points[i].observations);
  }
  o.seed = 2;
  const SynthDataset c = MakeSynthDataset(o, context_);
  EXPECT_GT(cv::norm(a.images[0], c.images[0], cv::NORM_L1) / a.images[0].total(), 5.0);
}

TEST_F(SynthTest, ImagesAreTexturedAndNoiseIsAdded) {
  SynthOptions o = Small("pyramid-down", 2);
  const SynthDataset clean = MakeSynthDataset(o, context_);
  // Texture inside the pyramid's image: a centred window has plenty of contrast.
  const cv::Mat centre = clean.images[0](cv::Rect(60, 40, 40, 40));
  cv::Scalar mean, stddev;
  cv::meanStdDev(centre, mean, stddev);
  EXPECT_GT(stddev[1], 10.0);
  o.image_noise = 4;
  const SynthDataset noisy = MakeSynthDataset(o, context_);
  cv::Mat difference;
  cv::absdiff(clean.images[0], noisy.images[0], difference);
  difference.convertTo(difference, CV_32F);
  cv::meanStdDev(difference.reshape(1), mean, stddev);
  EXPECT_NEAR(mean[0], 4 * std::sqrt(2 / M_PI), 0.6);  // E|N(0, 4)|, less rounding/saturation
}

TEST_F(SynthTest, PointNoiseMovesPointsButNotTheirObservations) {
  SynthOptions o = Small("blob", 6);
  o.points = 400;
  o.render_images = false;
  const SynthDataset clean = MakeSynthDataset(o, nullptr);
  o.point_noise = 0.02;
  const SynthDataset noisy = MakeSynthDataset(o, nullptr);
  ASSERT_EQ(clean.scene.points.size(), noisy.scene.points.size());
  double sum_sq = 0;
  for (size_t i = 0; i < clean.scene.points.size(); ++i) {
    EXPECT_EQ(clean.scene.points[i].observations, noisy.scene.points[i].observations);
    EXPECT_EQ(noisy.exact_points[i], clean.scene.points[i].position);
    sum_sq += (noisy.scene.points[i].position - clean.scene.points[i].position).squaredNorm();
  }
  const double sigma = std::sqrt(sum_sq / (3 * clean.scene.points.size()));
  EXPECT_NEAR(sigma, 0.02, 0.003);
}

// Every observation of a sparse point is unoccluded in the ground-truth depth map of its view,
// and views that do not list a point (while it is in their image, near and facing them) have
// something in front of it: the CPU ray casting agrees with the GL depth test.
void CheckVisibilityAgainstDepthMaps(const SynthDataset& d, const gl::GlContext& context,
                                     double max_distance) {
  gl::MeshRenderer renderer(context, d.ground_truth);
  std::vector<cv::Mat> depth;
  for (const View& v : d.scene.views) {
    gl::DepthRenderOptions options;
    options.world_positions = false;
    options.face_ids = false;
    depth.push_back(renderer.Render(v, options).depth);
  }
  int64_t observations = 0, hidden_checked = 0, hidden_confirmed = 0, visible_ok = 0;
  for (size_t i = 0; i < d.scene.points.size(); ++i) {
    const Eigen::Vector3d& p = d.exact_points[i];
    const Eigen::Vector3d normal = d.ground_truth.FaceNormal(d.point_faces[i]);
    std::vector<bool> seen(d.scene.views.size(), false);
    for (const Observation& ob : d.scene.points[i].observations) {
      seen[ob.view] = true;
      const View& view = d.scene.views[ob.view];
      const double z = view.ToCamera(p).z();
      const cv::Mat& map = depth[ob.view];
      const int col = static_cast<int>(ob.x), row = static_cast<int>(ob.y);
      // Unoccluded: the map at the point's pixel is at the point's depth (pixel-centre offset
      // and slope allow ~1%), or a neighbouring pixel is (an occluding edge crossing the pixel).
      bool ok = map.at<float>(row, col) > z * 0.99;
      visible_ok += ok;
      for (int dr = -1; dr <= 1 && !ok; ++dr) {
        for (int dc = -1; dc <= 1 && !ok; ++dc) {
          const int r = std::clamp(row + dr, 0, map.rows - 1);
          const int c = std::clamp(col + dc, 0, map.cols - 1);
          ok = map.at<float>(r, c) > z * 0.99;
        }
      }
      ASSERT_TRUE(ok) << "point " << i << " observed in view " << ob.view << " is occluded";
      ++observations;
    }
    for (size_t v = 0; v < d.scene.views.size(); ++v) {
      if (seen[v]) continue;
      const View& view = d.scene.views[v];
      Eigen::Vector2d pixel;
      if (!view.Project(p, &pixel)) continue;
      const Eigen::Vector3d to_camera = view.Center() - p;
      if (pixel.x() < 2 || pixel.y() < 2 || pixel.x() > view.intrinsics.width - 2 ||
          pixel.y() > view.intrinsics.height - 2 ||
          normal.dot(to_camera.normalized()) < std::cos(70 * M_PI / 180) ||
          (max_distance > 0 && to_camera.norm() > max_distance * 0.98)) {
        continue;  // not seen for other reasons than occlusion (or too close to call)
      }
      // Hidden: something lies in front of the point at its pixel or a neighbouring one (an
      // occluding edge within a pixel of the exact ray is too close to call from pixel centres).
      const double z = view.ToCamera(p).z();
      const int col = static_cast<int>(pixel.x()), row = static_cast<int>(pixel.y());
      bool hidden = false;
      for (int dr = -1; dr <= 1 && !hidden; ++dr) {
        for (int dc = -1; dc <= 1 && !hidden; ++dc) {
          const float d_map = depth[v].at<float>(row + dr, col + dc);
          hidden = d_map > 0 && d_map < z * 0.99;
        }
      }
      ++hidden_checked;
      hidden_confirmed += hidden;
    }
  }
  std::printf(
      "%ld observations (%.2f%% exact at their pixel), %ld unlisted in-view sightings, "
      "%.2f%% of them occluded in the depth map\n",
      static_cast<long>(observations), 100.0 * visible_ok / observations,
      static_cast<long>(hidden_checked),
      hidden_checked ? 100.0 * hidden_confirmed / hidden_checked : 100.0);
  EXPECT_GT(observations, 0);
  EXPECT_GT(visible_ok, 0.98 * observations);
  EXPECT_EQ(hidden_confirmed, hidden_checked);
}

TEST_F(SynthTest, BlobVisibilityAgreesWithDepthMaps) {
  SynthOptions o = Small("blob", 8);
  o.width = 320;
  o.height = 240;
  o.points = 1500;
  o.render_images = false;
  const SynthDataset d = MakeSynthDataset(o, nullptr);
  EXPECT_GT(d.scene.points.size(), 1400u);
  for (const ScenePoint& p : d.scene.points) EXPECT_GE(p.observations.size(), 2u);
  CheckVisibilityAgainstDepthMaps(d, *context_, 0);
}

TEST_F(SynthTest, CityVisibilityAgreesWithDepthMaps) {
  SynthOptions o = Small("city", 16);
  o.width = 320;
  o.height = 240;
  o.points = 2000;
  o.render_images = false;
  const SynthDataset d = MakeSynthDataset(o, nullptr);
  EXPECT_GT(d.scene.points.size(), 1500u);
  CheckVisibilityAgainstDepthMaps(d, *context_, 50);
}

TEST_F(SynthTest, CityImagesRender) {
  SynthOptions o = Small("city", 2);
  const SynthDataset d = MakeSynthDataset(o, context_);
  ASSERT_EQ(d.images.size(), 2u);
  cv::Scalar mean, stddev;
  cv::meanStdDev(d.images[0], mean, stddev);
  EXPECT_GT(stddev[1], 10.0);
}

TEST(Synth, CityScalesToThousandsOfCamerasWithoutImages) {
  SynthOptions o;
  o.scene = "city";
  o.views = 1000;
  o.render_images = false;
  Timer timer;
  const SynthDataset d = MakeSynthDataset(o, nullptr);
  const double seconds = timer.Seconds();
  std::printf("city, 1000 views without images: %.2f s (geometry %.2f s, points %.2f s), %s\n",
              seconds, d.seconds_geometry, d.seconds_points, d.scene.Summary().c_str());
  EXPECT_EQ(d.scene.views.size(), 1000u);
  EXPECT_GT(d.scene.points.size(), 38000u);  // 40 per view asked
  EXPECT_TRUE(d.images.empty());
  // Every view sees some points.
  std::vector<int> per_view(d.scene.views.size(), 0);
  for (const ScenePoint& p : d.scene.points) {
    for (const Observation& ob : p.observations) ++per_view[ob.view];
  }
  EXPECT_GT(*std::min_element(per_view.begin(), per_view.end()), 20);
}

TEST(Synth, ImagesNeedAContext) {
  SynthOptions o = Small("pyramid-down", 2);
  EXPECT_THROW(MakeSynthDataset(o, nullptr), InternalError);
}

}  // namespace
}  // namespace ms
