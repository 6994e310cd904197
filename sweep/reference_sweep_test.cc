#include "sweep/reference_sweep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tuple>

#include "base/error.h"
#include "testing/sweep_test_scene.h"
#include "testing/testing.h"

namespace ms {
namespace {

// ---- NCC ----

TEST(WeightedNcc, SelfNegativeAndAffine) {
  const cv::Mat I = BlurredNoiseImage(64, 48, 1);
  const cv::Mat mask(I.size(), CV_8U, cv::Scalar(255));
  const cv::Mat window = GaussianWindow(4);
  cv::Mat ncc;
  EXPECT_EQ(WeightedNcc(I, I, mask, window, 1e-4, 0.2, &ncc), 64 * 48);
  for (int r = 0; r < I.rows; ++r) {
    for (int c = 0; c < I.cols; ++c) ASSERT_NEAR(ncc.at<float>(r, c), 1.0, 1e-6);
  }
  const cv::Mat negative = 1.0 - I;
  WeightedNcc(I, negative, mask, window, 1e-4, 0.2, &ncc);
  for (int r = 0; r < I.rows; ++r) {
    for (int c = 0; c < I.cols; ++c) ASSERT_NEAR(ncc.at<float>(r, c), -1.0, 1e-5);
  }
  const cv::Mat affine = 0.4 * I + 0.35;
  WeightedNcc(I, affine, mask, window, 1e-5, 0.2, &ncc);
  for (int r = 0; r < I.rows; ++r) {
    for (int c = 0; c < I.cols; ++c) ASSERT_NEAR(ncc.at<float>(r, c), 1.0, 1e-4);
  }
  // An unrelated image correlates weakly.
  WeightedNcc(I, BlurredNoiseImage(64, 48, 2), mask, window, 1e-4, 0.2, &ncc);
  EXPECT_LT(std::abs(ncc.at<float>(24, 32)), 0.6);
}

TEST(WeightedNcc, MaskVarianceAndWindowWeight) {
  const cv::Mat I = BlurredNoiseImage(64, 48, 3);
  cv::Mat J = I.clone();
  cv::Mat mask(I.size(), CV_8U, cv::Scalar(255));
  // Right half of J is garbage but masked out: only valid pixels count, so NCC stays 1 on the
  // left half; masked pixels themselves are undefined.
  J(cv::Rect(32, 0, 32, 48)) = BlurredNoiseImage(32, 48, 4);
  mask(cv::Rect(32, 0, 32, 48)) = 0;
  const cv::Mat window = GaussianWindow(3);
  cv::Mat ncc;
  WeightedNcc(I, J, mask, window, 1e-4, 0.3, &ncc);
  EXPECT_NEAR(ncc.at<float>(20, 30), 1.0, 1e-5);
  EXPECT_TRUE(std::isnan(ncc.at<float>(20, 40)));
  // Near the mask border the valid weight is about half; a higher bound rejects it.
  WeightedNcc(I, J, mask, window, 1e-4, 0.6, &ncc);
  EXPECT_TRUE(std::isnan(ncc.at<float>(20, 31)));
  EXPECT_NEAR(ncc.at<float>(20, 20), 1.0, 1e-5);
  // Textureless: a constant image, or variance below the bound.
  const cv::Mat flat(I.size(), CV_32F, cv::Scalar(0.7));
  EXPECT_EQ(WeightedNcc(flat, flat, mask, window, 0, 0.3, &ncc), 0);
  const cv::Mat faint = 0.5 + 0.01 * (I - 0.5);  // variance ~1e-6
  EXPECT_EQ(WeightedNcc(faint, faint, mask, window, 1e-4, 0.3, &ncc), 0);
  EXPECT_GT(WeightedNcc(faint, faint, mask, window, 1e-8, 0.3, &ncc), 0);
}

// ---- Reprojection ----

TEST(ReprojectNeighbour, BilinearSamplesAndShadowMapOcclusion) {
  View camera;
  camera.intrinsics = {64, 48, 50, 50, 32, 24};
  View neighbour = camera;
  neighbour.SetCenter({1, 0, 0});
  // The neighbour's image is a ramp, so bilinear sampling is exact: value(u, v) at texel
  // coordinates (u - 0.5, v - 0.5).
  cv::Mat image(48, 64, CV_32F);
  for (int r = 0; r < 48; ++r) {
    for (int c = 0; c < 64; ++c) image.at<float>(r, c) = 0.01f * c + 0.02f * r;
  }
  const auto quad = [](SoftwareRasterizer* raster, double z, double x0, double x1, double y0,
                       double y1, int face) {
    raster->DrawTriangle({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, face);
    raster->DrawTriangle({x0, y0, z}, {x1, y1, z}, {x0, y1, z}, face);
  };
  SoftwareRasterizer c_raster(camera, 0.01, true);
  quad(&c_raster, 5, -20, 20, -20, 20, 0);  // the plane z = 5
  SoftwareRasterizer shadow(neighbour, 0.01, false);
  quad(&shadow, 5, -20, 20, -20, 20, 0);
  quad(&shadow, 2.5, 0.8, 1.2, -0.2, 0.2, 1);  // an occluder in front of the neighbour only
  cv::Mat reprojected, mask;
  ReprojectNeighbour(c_raster, neighbour, image, shadow, 0.01, &reprojected, &mask);
  int occluded = 0, valid = 0;
  for (int r = 0; r < 48; ++r) {
    for (int c = 0; c < 64; ++c) {
      const Eigen::Vector3d P =
          camera.PixelRay({c + 0.5, r + 0.5}) * 5 / camera.PixelRay({c + 0.5, r + 0.5}).z();
      Eigen::Vector2d uv;
      ASSERT_TRUE(neighbour.Project(P, &uv));
      const double edge = std::min({uv.x() - 0.5, 63.5 - uv.x(), uv.y() - 0.5, 47.5 - uv.y()});
      if (std::abs(edge) < 1e-6) continue;  // exactly on the valid region's border
      const bool inside = edge > 0;
      // Where the segment to the neighbour's centre crosses z = 2.5.
      const Eigen::Vector3d mid = 0.5 * (P + Eigen::Vector3d(1, 0, 0));
      const double margin = std::max(std::abs(mid.x() - 1), std::abs(mid.y())) - 0.2;
      if (std::abs(margin) < 0.02) continue;  // shadow-map texel on the occluder's border
      const bool blocked = margin < 0;
      occluded += inside && blocked;
      const bool expect_valid = inside && !blocked;
      EXPECT_EQ(mask.at<uint8_t>(r, c) != 0, expect_valid) << c << "," << r;
      if (expect_valid) {
        ++valid;
        EXPECT_NEAR(reprojected.at<float>(r, c), 0.01 * (uv.x() - 0.5) + 0.02 * (uv.y() - 0.5),
                    1e-5);
      }
    }
  }
  EXPECT_GT(occluded, 20);
  EXPECT_GT(valid, 1000);
}

// ---- Shared preparation ----

TEST(SweepKernel, OffsetsFollowTheStrictInequality) {
  EXPECT_EQ(SweepOffsets(20).front(), -9);
  EXPECT_EQ(SweepOffsets(20).back(), 9);
  EXPECT_EQ(SweepOffsets(20).size(), 19u);
  EXPECT_EQ(SweepOffsets(5), (std::vector<int>{-2, -1, 0, 1, 2}));
  EXPECT_EQ(SweepOffsets(2), (std::vector<int>{0}));
  EXPECT_EQ(SweepOffsets(1), (std::vector<int>{0}));
}

TEST(SweepKernel, SweepVertexMovesAlongTheRayByCosine) {
  const Eigen::Vector3d c(0, 0, 0), v(0, 3, 4);  // |v - c| = 5
  const Eigen::Vector3d d = v / 5;
  const Eigen::Vector3d n(0, 0, -1);  // facing the camera: cos(theta) = n.d = -0.8
  EXPECT_LT((SweepVertex(v, n, c, 0.5) - (v + 0.4 * d)).norm(), 1e-12);
  EXPECT_LT((SweepVertex(v, -n, c, 0.5) - (v + 0.4 * d)).norm(), 1e-12);  // orientation-free
  EXPECT_LT((SweepVertex(v, n, c, -0.5) - (v - 0.4 * d)).norm(), 1e-12);
  EXPECT_EQ(SweepVertex(v, Eigen::Vector3d::Zero(), c, 0.5), v);  // degenerate facet
}

TEST(SweepKernel, TileGridSplitsEvenly) {
  const TileGrid grid = TileGrid::Make(1536, 1024, 100);
  EXPECT_EQ(grid.tiles_x, 15);
  EXPECT_EQ(grid.tiles_y, 10);
  EXPECT_EQ(grid.XBegin(0), 0);
  EXPECT_EQ(grid.XBegin(1), 102);
  EXPECT_EQ(grid.XBegin(15), 1536);
  const TileGrid small = TileGrid::Make(30, 20, 100);
  EXPECT_EQ(small.NumTiles(), 1);
}

TEST(SweepKernel, TileGridCountsTilesPerImage) {
  SweepOptions options;
  EXPECT_EQ(options.tile_size_px, 100);
  EXPECT_EQ(options.tiles_across, 0);
  EXPECT_EQ(TileGrid::ForOptions(1536, 1024, options).tiles_x, 15);
  // The longer side has tiles_across tiles whatever the resolution or orientation.
  options.tiles_across = 16;
  for (const auto& [w, h, tiles_y] : {std::tuple{3072, 2048, 11}, std::tuple{1536, 1024, 11},
                                      std::tuple{640, 480, 12}, std::tuple{1600, 1200, 12}}) {
    TileGrid grid = TileGrid::ForOptions(w, h, options);
    EXPECT_EQ(grid.tiles_x, 16) << w << "x" << h;
    EXPECT_EQ(grid.tiles_y, tiles_y) << w << "x" << h;
    grid = TileGrid::ForOptions(h, w, options);
    EXPECT_EQ(grid.tiles_x, tiles_y) << h << "x" << w;
    EXPECT_EQ(grid.tiles_y, 16) << h << "x" << w;
  }
  // Tiny images get one tile per pixel at most.
  options.tiles_across = 64;
  const TileGrid tiny = TileGrid::ForOptions(8, 3, options);
  EXPECT_EQ(tiny.tiles_x, 8);
  EXPECT_EQ(tiny.tiles_y, 3);
}

TEST(SweepKernel, GaussianWindowIsNormalised) {
  const cv::Mat w = GaussianWindow(8);
  EXPECT_EQ(w.rows, 49);
  EXPECT_NEAR(cv::sum(w)[0], 1.0, 1e-6);
  EXPECT_NEAR(w.at<float>(24) / w.at<float>(32), std::exp(0.5), 1e-5);
}

TEST(SweepKernel, AutoAlphaGivesTheRequestedParallax) {
  // C at the origin looking down +z, a neighbour 2 units to the side, a point on the axis at
  // depth 4: moving it along the ray by s shifts it by f b s / z^2 = 25 s pixels.
  View camera;
  camera.intrinsics = {400, 300, 200, 200, 200, 150};
  View neighbour = camera;
  neighbour.SetCenter({2, 0, 0});
  Mesh mesh;
  mesh.vertices = {{0, 0, 4}};
  EXPECT_NEAR(AutoSweepAlpha(camera, {neighbour}, mesh, 1.0, 4), 1.0 / 25, 1e-12);
  EXPECT_NEAR(AutoSweepAlpha(camera, {neighbour}, mesh, 0.5, 4), 0.5 / 25, 1e-12);
  // Clamped to 2% of the median depth when the parallax is weak.
  EXPECT_NEAR(AutoSweepAlpha(camera, {neighbour}, mesh, 5.0, 4), 0.08, 1e-12);
}

TEST(SweepKernel, PrepareSweepChoosesThePyramidLevel) {
  SweepJob job;
  job.camera.id = 0;
  job.camera.view.intrinsics = {3072, 2048, 2760, 2760, 1536.5, 1024.25};
  job.camera.image = cv::Mat(2048, 3072, CV_32F, cv::Scalar(0.5));
  SweepCamera neighbour = job.camera;
  neighbour.id = 1;
  neighbour.view.SetCenter({1, 0, 0});
  job.neighbours = {neighbour};
  job.mesh = MakeFlatSquare(0, 1, 1);
  for (auto& v : job.mesh.vertices) v.z() = 10;
  std::swap(job.mesh.faces[0][1], job.mesh.faces[0][2]);  // facing the camera at the origin
  PreparedSweep prep = PrepareSweep(job);
  EXPECT_EQ(prep.pyramid_level, 1);
  EXPECT_EQ(prep.camera.image.size(), cv::Size(1536, 1024));
  EXPECT_DOUBLE_EQ(prep.camera.view.intrinsics.fx, 1380);
  EXPECT_DOUBLE_EQ(prep.camera.view.intrinsics.cx, 768.25);
  EXPECT_DOUBLE_EQ(prep.camera.view.intrinsics.cy, 512.125);
  EXPECT_EQ(prep.neighbours[0].image.size(), cv::Size(1536, 1024));
  EXPECT_EQ(prep.tiles.tiles_x, 15);
  EXPECT_DOUBLE_EQ(prep.median_depth, 10);
  // Tiles counted per image: the same count at the full-size level below.
  job.options.tiles_across = 16;
  EXPECT_EQ(PrepareSweep(job).tiles.tiles_x, 16);
  EXPECT_EQ(PrepareSweep(job).tiles.tiles_y, 11);
  job.options.tiles_across = 0;
  job.options.alpha = 0.03;
  job.options.max_image_dimension = 0;
  prep = PrepareSweep(job);
  EXPECT_EQ(prep.pyramid_level, 0);
  EXPECT_EQ(prep.tiles.tiles_x, 31);
  job.options.tiles_across = 16;
  EXPECT_EQ(PrepareSweep(job).tiles.tiles_x, 16);
  job.options.tiles_across = 0;
  EXPECT_EQ(prep.alpha, 0.03);
  job.options.pyramid_level = 2;
  EXPECT_EQ(PrepareSweep(job).camera.image.size(), cv::Size(768, 512));
}

// ---- The pyramid ----

struct PyramidFixture {
  PyramidScene scene;
  SweepJob job;
};

std::vector<double> SortedDistances(const PyramidScene& scene, const SweepResult& result) {
  std::vector<double> d;
  for (const SweepPoint& p : result.points) d.push_back(scene.Distance(p.position));
  std::sort(d.begin(), d.end());
  return d;
}

double Quantile(const std::vector<double>& sorted, double q) {
  return sorted[static_cast<size_t>(q * (sorted.size() - 1))];
}

TEST(ReferenceSweep, PyramidFromAFlatSquare) {
  PyramidSceneOptions options;
  options.noise_stddev = 0.01;  // sensor noise, independent per camera
  const PyramidScene scene = MakePyramidScene(options);
  const Mesh square = MakeFlatSquare(0.15, 1.3, 8);
  const SweepJob job = MakeSmallSweepJob(scene, square);
  ReferenceSweepKernel kernel;
  const SweepResult result = kernel.Run(job);
  const SweepStats& s = result.stats;
  EXPECT_EQ(s.image_width, 160);
  EXPECT_EQ(s.num_offsets, 19);
  EXPECT_EQ(s.tiles_x * s.tiles_y, 16 * 12);
  EXPECT_EQ(s.hypotheses, int64_t{160} * 120 * 19 * 2);
  ASSERT_GT(result.points.size(), 40u) << s.Summary();

  // Initial error of the square: mean distance over a grid of its points.
  double initial = 0;
  for (int i = 0; i < 21; ++i) {
    for (int j = 0; j < 21; ++j) {
      initial += scene.Distance({-1 + 0.1 * i, -1 + 0.1 * j, 0.15});
    }
  }
  initial /= 21 * 21;
  const std::vector<double> d = SortedDistances(scene, result);
  const double median = Quantile(d, 0.5), p90 = Quantile(d, 0.9);
  std::printf(
      "pyramid: %zu points, distance to truth median %.4f p90 %.4f (initial mean %.4f)\n"
      "  %s\n",
      result.points.size(), median, p90, initial, s.Summary().c_str());
  EXPECT_LT(median, 0.01);
  EXPECT_LT(p90, 0.03);
  for (const SweepPoint& p : result.points) {
    EXPECT_GT(p.ncc, 0.98);
    ASSERT_GE(p.cameras.size(), 2u);
    EXPECT_EQ(p.cameras[0], 0);
    EXPECT_TRUE(p.cameras[1] == 1 || p.cameras[1] == 2);
    EXPECT_GE(p.offset, -9);
    EXPECT_LE(p.offset, 9);
    // The point lies on C's ray through its pixel.
    const Eigen::Vector3d ray = job.camera.view.PixelRay(p.pixel.cast<double>());
    const Eigen::Vector3d to_point = (p.position - job.camera.view.Center()).normalized();
    EXPECT_LT((ray - to_point).norm(), 1e-5);
  }
}

// Swept at the true surface, the paper's rule finds it at k = 0 in most tiles. Where winners must
// move, k = 0 competes for nothing and an offset wins only where it matches better than the
// surface, which the true surface leaves to a few pixels.
TEST(ReferenceSweep, TrueMeshMatchesAtOffsetZero) {
  const PyramidScene scene = MakePyramidScene();
  SweepJob job = MakeSmallSweepJob(scene, scene.truth);
  job.options.num_offsets = 3;
  job.options.alpha = 0.05;
  job.options.strict_support = false;
  job.options.winners_must_move = false;
  const SweepResult paper = ReferenceSweepKernel().Run(job);
  ASSERT_GT(paper.points.size(), 100u) << paper.stats.Summary();
  int at_zero = 0;
  for (const SweepPoint& p : paper.points) {
    at_zero += p.offset == 0;
    EXPECT_LT(scene.Distance(p.position), p.offset == 0 ? 1e-9 : 0.06);
  }
  EXPECT_GT(at_zero, 0.9 * paper.points.size());
  job.options.winners_must_move = true;
  const SweepResult moving = ReferenceSweepKernel().Run(job);
  std::printf(
      "true mesh: %zu points with the paper's rule (%d at k = 0), %zu where winners must move\n",
      paper.points.size(), at_zero, moving.points.size());
  for (const SweepPoint& p : moving.points) {
    EXPECT_NE(p.offset, 0);
    EXPECT_LT(scene.Distance(p.position), 0.06);  // one step
  }
  EXPECT_LT(moving.points.size(), 0.1 * paper.points.size());
}

TEST(ReferenceSweep, BlankAndFaintTexturesFindNothing) {
  const Mesh square = MakeFlatSquare(0.15, 1.3, 8);
  PyramidSceneOptions blank;
  blank.texture_contrast = 0;
  const PyramidScene blank_scene = MakePyramidScene(blank);
  const SweepResult none = ReferenceSweepKernel().Run(MakeSmallSweepJob(blank_scene, square));
  EXPECT_EQ(none.points.size(), 0u);
  EXPECT_EQ(none.stats.valid_hypotheses, 0);

  // A consistent texture too faint to trust (std ~0.003 < 0.01): rejected by the variance bound
  // alone; without the bound the same images match.
  PyramidSceneOptions faint;
  faint.texture_contrast = 0.015;
  const PyramidScene faint_scene = MakePyramidScene(faint);
  SweepJob job = MakeSmallSweepJob(faint_scene, square);
  EXPECT_EQ(ReferenceSweepKernel().Run(job).points.size(), 0u);
  job.options.min_texture_variance = 0;
  EXPECT_GT(ReferenceSweepKernel().Run(job).points.size(), 10u);
}

TEST(ReferenceSweep, PyramidLevelSweepsAtHalfResolution) {
  PyramidSceneOptions options;
  options.width = 320;
  options.height = 240;
  const PyramidScene scene = MakePyramidScene(options);
  SweepJob job = MakeSmallSweepJob(scene, MakeFlatSquare(0.15, 1.3, 8));
  job.options.max_image_dimension = 200;
  const SweepResult result = ReferenceSweepKernel().Run(job);
  EXPECT_EQ(result.stats.pyramid_level, 1);
  EXPECT_EQ(result.stats.image_width, 160);
  EXPECT_EQ(result.stats.image_height, 120);
  ASSERT_GT(result.points.size(), 20u);
  for (const SweepPoint& p : result.points) {
    // Pixels are reported in full-resolution coordinates: centres of 2x2 blocks.
    EXPECT_FLOAT_EQ(std::fmod(p.pixel.x(), 2.0f), 1.0f);
    const Eigen::Vector3d ray = job.camera.view.PixelRay(p.pixel.cast<double>());
    EXPECT_LT((ray - (p.position - job.camera.view.Center()).normalized()).norm(), 1e-5);
  }
  const std::vector<double> d = SortedDistances(scene, result);
  EXPECT_LT(Quantile(d, 0.5), 0.02);
}

TEST(ReferenceSweep, Deterministic) {
  const PyramidScene scene = MakePyramidScene();
  const SweepJob job = MakeSmallSweepJob(scene, MakeFlatSquare(0.12, 1.3, 4));
  const SweepResult a = ReferenceSweepKernel().Run(job);
  const SweepResult b = ReferenceSweepKernel().Run(job);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].position, b.points[i].position);
    EXPECT_EQ(a.points[i].ncc, b.points[i].ncc);
    EXPECT_EQ(a.points[i].cameras, b.points[i].cameras);
  }
}

// ---- Bad jobs ----

void ExpectInputError(const SweepJob& job, const std::string& fragment) {
  testing::ExpectInputError([&] { ReferenceSweepKernel().Run(job); }, {fragment});
}

TEST(ReferenceSweep, BadJobsThrowInputError) {
  const SweepJob good = MakeTinyValidSweepJob();
  EXPECT_NO_THROW(ReferenceSweepKernel().Run(good));

  SweepJob job = good;
  job.mesh = Mesh();
  ExpectInputError(job, "mesh has no faces");
  job = good;
  job.mesh.faces[0][1] = 1000;
  ExpectInputError(job, "refers to vertex 1000");
  job = good;
  job.mesh.vertices[0].x() = std::nan("");
  ExpectInputError(job, "not finite");
  job = good;
  // Camera outside the scene: moved under the ground, looking away from the mesh.
  job.camera.view.SetCenter({0, 0, -5});
  ExpectInputError(job, "no face of the mesh is in front of the camera");
  job = good;
  job.camera.image = cv::Mat();
  ExpectInputError(job, "camera 0 ('pyramid_0'): image missing");
  job = good;
  job.neighbours[1].image = cv::Mat(31, 40, CV_32F, cv::Scalar(0.5));
  ExpectInputError(job,
                   "neighbour 2 ('pyramid_2'): image is 40x31 but the view's intrinsics say 40x30");
  job = good;
  job.neighbours[0].image.convertTo(job.neighbours[0].image, CV_8U, 255);
  ExpectInputError(job, "CV_32FC1");
  job = good;
  job.camera.image = job.camera.image.clone();  // cv::Mat copies share pixels
  job.camera.image.at<float>(3, 3) = std::numeric_limits<float>::infinity();
  ExpectInputError(job, "non-finite");
  job = good;
  job.neighbours.clear();
  ExpectInputError(job, "no neighbour");
  job = good;
  job.neighbours[0].view.SetCenter(job.camera.view.Center());
  ExpectInputError(job, "at the camera's centre");
  job = good;
  job.neighbours[0].id = 0;
  ExpectInputError(job, "its own neighbour");
  job = good;
  job.camera.view.intrinsics.k1 = 0.1;
  ExpectInputError(job, "distortion");
  job = good;
  job.camera.view.intrinsics.fx = 0;
  ExpectInputError(job, "focal length");
  job = good;
  job.options.num_offsets = 0;
  ExpectInputError(job, "--sweep.num-offsets");
  job = good;
  job.options.ncc_threshold = 2;
  ExpectInputError(job, "--sweep.ncc-threshold");
  job = good;
  job.options.alpha = -1;
  ExpectInputError(job, "--sweep.alpha");
}

}  // namespace
}  // namespace ms
