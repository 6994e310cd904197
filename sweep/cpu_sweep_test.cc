// The fast CPU kernel (sweep/cpu_sweep.h) against the exact reference, piece by piece: the
// recursive Gaussian against GaussianWindow, the span rasteriser against SoftwareRasterizer, the
// recursive NCC against WeightedNcc, and end to end the same tile winners on the parity scenes
// (the GLSL kernel's, sweep/glsl_sweep_test.cc). Tolerances are those of docs/design/sweep.md.
#include "sweep/cpu_sweep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "base/error.h"
#include "sweep/recursive_gaussian.h"
#include "sweep/reference_sweep.h"
#include "sweep/software_raster.h"
#include "sweep/span_raster.h"
#include "sweep/subnormals.h"
#include "sweep/windowed_ncc.h"
#include "testing/sweep_parity_testing.h"
#include "testing/sweep_test_scene.h"
#include "testing/testing.h"

namespace ms {
namespace {

// ---- The recursive Gaussian ----

TEST(RecursiveGaussian, TapsFollowTheTruncatedGaussian) {
  for (double sigma : {0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 24.0}) {
    SCOPED_TRACE(sigma);
    const RecursiveGaussian g = RecursiveGaussian::Make(sigma);
    const cv::Mat window = GaussianWindow(sigma);
    ASSERT_EQ(window.rows, 2 * g.radius + 1);
    double peak = 0, worst = 0, l1 = 0, sum = 0;
    for (int m = -g.radius; m <= g.radius; ++m) {
      const double exact = window.at<float>(m + g.radius);
      peak = std::max(peak, exact);
      worst = std::max(worst, std::abs(g.Tap(m) - exact));
      l1 += std::abs(g.Tap(m) - exact);
      sum += g.Tap(m);
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    EXPECT_EQ(g.Tap(g.radius + 1), 0);
    EXPECT_LT(worst, 6e-4 * peak);  // docs/design/sweep.md
    EXPECT_LT(l1, 1e-3);
  }
}

TEST(RecursiveGaussian, RecursionsEqualTheTruncatedConvolution) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (double sigma : {0.7, 3.0, 8.0}) {
    const RecursiveGaussian g = RecursiveGaussian::Make(sigma);
    for (int n : {1, 5, 40, 100}) {  // shorter and longer than the window
      std::vector<double> x(n);
      for (double& v : x) v = uniform(rng);
      const std::vector<double> y = RecursiveGaussianFilter(g, x);
      for (int i = 0; i < n; ++i) {
        double direct = 0;
        for (int m = -g.radius; m <= g.radius; ++m) {
          if (i + m >= 0 && i + m < n) direct += g.Tap(m) * x[i + m];
        }
        ASSERT_NEAR(y[i], direct, 1e-12) << "sigma " << sigma << " n " << n << " i " << i;
      }
    }
  }
}

// ---- The span rasteriser ----

TEST(SpanRasterizer, SamePixelsAsTheSoftwareRasterizer) {
  View view = LookAtView({0.3, -0.2, 3}, {0, 0, 0}, 97, 61, 90);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> xy(-1.6, 1.6), z(-0.5, 2.9);
  SoftwareRasterizer reference(view, 0.05, true);
  SpanRasterizer fast(view, 0.05, true);
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;
  // A fan sharing edges and vertices (fill rule), random triangles, some crossing the near
  // plane (z up to 2.9 with the camera at 3) and some seen edge on.
  const Eigen::Vector3d hub(0.05, 0.02, 0.1);
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * M_PI * i / 12, b = 2 * M_PI * (i + 1) / 12;
    triangles.push_back({hub, Eigen::Vector3d(std::cos(a), std::sin(a), 0),
                         Eigen::Vector3d(std::cos(b), std::sin(b), 0)});
  }
  for (int i = 0; i < 60; ++i) {
    triangles.push_back({Eigen::Vector3d(xy(rng), xy(rng), z(rng)),
                         Eigen::Vector3d(xy(rng), xy(rng), z(rng)),
                         Eigen::Vector3d(xy(rng), xy(rng), z(rng))});
  }
  triangles.push_back(
      {Eigen::Vector3d(0.3, -0.2, 1), Eigen::Vector3d(0.3, -0.2, 2), Eigen::Vector3d(0.5, 0.5, 1)});
  for (size_t f = 0; f < triangles.size(); ++f) {
    const auto& t = triangles[f];
    reference.DrawTriangle(t[0], t[1], t[2], static_cast<int32_t>(f));
  }
  fast.DrawSoup(triangles);
  int covered = 0, different_face = 0;
  for (int row = 0; row < view.intrinsics.height; ++row) {
    for (int col = 0; col < view.intrinsics.width; ++col) {
      const size_t i = reference.Index(col, row);
      const int32_t f = reference.face()[i];
      ASSERT_EQ(f >= 0, fast.face()[i] >= 0) << col << "," << row;
      if (f < 0) continue;
      ++covered;
      // Near-equal depths of two triangles may resolve differently in float.
      if (fast.face()[i] != f) {
        ++different_face;
        continue;
      }
      ASSERT_NEAR(1.0 / fast.inverse_depth()[i], reference.depth()[i], 1e-5 * reference.depth()[i]);
    }
  }
  EXPECT_GT(covered, 3000);
  EXPECT_LE(different_face, covered / 1000);
}

// Triangle by triangle, each into a cleared target: the span rasteriser covers exactly the
// software rasteriser's pixels, also where edges pass through pixel centres (vertices on the
// half-pixel grid, where the fill rule decides), for slivers a pixel or less wide and across
// many rows, and for edges whose crossing of a row lands next to an integer.
TEST(SpanRasterizer, EveryTriangleCoversTheSoftwareRasterizersPixels) {
  View view;
  view.intrinsics = {160, 120, 1, 1, 0, 0};  // (u, v, 1) projects to pixel (u, v)
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> half_x(-10, 330), half_y(-10, 250);
  std::uniform_real_distribution<double> any_x(-5, 165), any_y(-5, 125), sliver(0.05, 1.5);
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;
  for (int i = 0; i < 400; ++i) {
    const auto on_grid = [&] { return Eigen::Vector3d(half_x(rng) * 0.5, half_y(rng) * 0.5, 1); };
    triangles.push_back({on_grid(), on_grid(), on_grid()});
    const Eigen::Vector3d a(any_x(rng), any_y(rng), 1), b(any_x(rng), any_y(rng), 1);
    const Eigen::Vector3d across = (b - a).cross(Eigen::Vector3d::UnitZ()).normalized();
    triangles.push_back({a, b, a + sliver(rng) * across});
    triangles.push_back({Eigen::Vector3d(any_x(rng), any_y(rng), 1),
                         Eigen::Vector3d(any_x(rng), any_y(rng), 1),
                         Eigen::Vector3d(any_x(rng), any_y(rng), 1)});
  }
  SoftwareRasterizer reference(view, 1e-3, true);
  SpanRasterizer fast(view, 1e-3, true);
  int64_t covered = 0;
  for (size_t f = 0; f < triangles.size(); ++f) {
    const auto& t = triangles[f];
    reference.Clear();
    reference.DrawTriangle(t[0], t[1], t[2], 0);
    fast.DrawSoup({t});
    for (size_t i = 0; i < reference.face().size(); ++i) {
      ASSERT_EQ(reference.face()[i] >= 0, fast.face()[i] >= 0)
          << "triangle " << f << ", pixel " << i % 160 << "," << i / 160;
      covered += reference.face()[i] >= 0;
    }
  }
  EXPECT_GT(covered, 100000);
}

// ---- The recursive NCC ----

TEST(WindowedNcc, MatchesWeightedNcc) {
  const int width = 131, height = 77;
  const cv::Mat I = BlurredNoiseImage(width, height, 1);
  // J: I warped a little, plus noise, with a mask that has holes, an edge band and a
  // ragged silhouette.
  cv::Mat J = 0.7 * I + 0.2 + 0.05 * BlurredNoiseImage(width, height, 2);
  cv::Mat mask(I.size(), CV_8U, cv::Scalar(255));
  mask(cv::Rect(90, 0, 41, 77)) = 0;
  cv::circle(mask, {40, 30}, 9, cv::Scalar(0), -1);
  for (int row = 0; row < height; ++row) mask.at<uint8_t>(row, 60 + row % 7) = 0;
  for (double sigma : {2.0, 4.0, 8.0}) {
    SCOPED_TRACE(sigma);
    cv::Mat expected;
    const int64_t defined = WeightedNcc(I, J, mask, GaussianWindow(sigma), 1e-4, 0.5, &expected);
    std::vector<float> j(width * height), m(width * height), ncc(width * height);
    for (int row = 0; row < height; ++row) {
      for (int col = 0; col < width; ++col) {
        const bool valid = mask.at<uint8_t>(row, col) != 0;
        j[row * width + col] = valid ? J.at<float>(row, col) - 0.5f : 0.0f;
        m[row * width + col] = valid ? 1.0f : 0.0f;
      }
    }
    WindowedNcc fast(width, height, sigma, 1e-4, 0.5);
    fast.SetCamera(I);
    const int64_t fast_defined = fast.Run(j.data(), m.data(), ncc.data());
    EXPECT_NEAR(static_cast<double>(fast_defined), defined, 0.002 * defined);
    double worst = 0;
    int only_one = 0;
    for (int i = 0; i < width * height; ++i) {
      const float e = expected.ptr<float>()[i];
      if (std::isnan(e) != std::isnan(ncc[i])) ++only_one;
      if (!std::isnan(e) && !std::isnan(ncc[i]))
        worst = std::max<double>(worst, std::abs(e - ncc[i]));
    }
    std::printf("sigma %.0f: %lld defined, %d defined in one only, worst NCC difference %.1e\n",
                sigma, static_cast<long long>(defined), only_one, worst);
    EXPECT_LE(only_one, 0.002 * defined);
    EXPECT_LT(worst, 2e-3);
  }
}

// The passes run over the rectangle around the valid pixels only. An image whose valid pixels
// reach all four edges, placed in a larger image with nothing valid around it, must get the
// same NCC bit for bit, and NaN everywhere around it.
TEST(WindowedNcc, ValidRectangleAloneGivesTheWholeImagesValues) {
  const int width = 75, height = 53;
  const cv::Mat I = BlurredNoiseImage(width, height, 3);
  const cv::Mat J = 0.6 * I + 0.3 + 0.05 * BlurredNoiseImage(width, height, 4);
  cv::Mat valid(I.size(), CV_8U, cv::Scalar(255));
  cv::circle(valid, {30, 20}, 7, cv::Scalar(0), -1);
  valid(cv::Rect(0, 0, 9, 6)) = 0;  // a corner out, the edges still reached
  for (int row = 0; row < height; ++row) valid.at<uint8_t>(row, 50 + row % 5) = 0;
  const double sigma = 4.0;
  const auto run = [&](int big_width, int big_height, int dx, int dy) {
    const size_t n = static_cast<size_t>(big_width) * big_height;
    std::vector<float> j(n, 0.0f), m(n, 0.0f), ncc(n);
    cv::Mat big_i(big_height, big_width, CV_32F, cv::Scalar(0.5f));
    I.copyTo(big_i(cv::Rect(dx, dy, width, height)));
    for (int row = 0; row < height; ++row) {
      for (int col = 0; col < width; ++col) {
        if (valid.at<uint8_t>(row, col) == 0) continue;
        const size_t i = static_cast<size_t>(row + dy) * big_width + col + dx;
        j[i] = J.at<float>(row, col) - 0.5f;
        m[i] = 1.0f;
      }
    }
    WindowedNcc windowed(big_width, big_height, sigma, 1e-4, 0.5);
    windowed.SetCamera(big_i);
    const int64_t defined = windowed.Run(j.data(), m.data(), ncc.data());
    return std::make_pair(defined, ncc);
  };
  const auto [defined, alone] = run(width, height, 0, 0);
  ASSERT_GT(defined, width * height / 2);
  // Offsets by whole groups of 8 columns, with and without columns to the right.
  for (const auto& [dx, dy, right, below] : std::vector<std::array<int, 4>>{{8, 5, 0, 19},
                                                                            {24, 13, 0, 0},
                                                                            {0, 1, 0, 7},
                                                                            {16, 0, 0, 33},
                                                                            {8, 3, 5, 2},
                                                                            {0, 0, 29, 0}}) {
    SCOPED_TRACE(::testing::Message() << "placed at " << dx << "," << dy);
    const int big_width = width + dx + right, big_height = height + dy + below;
    const auto [big_defined, placed] = run(big_width, big_height, dx, dy);
    EXPECT_EQ(big_defined, defined);
    int64_t differ = 0, not_nan_outside = 0;
    for (int row = 0; row < big_height; ++row) {
      for (int col = 0; col < big_width; ++col) {
        const float v = placed[static_cast<size_t>(row) * big_width + col];
        const int r = row - dy, c = col - dx;
        if (r < 0 || r >= height || c < 0 || c >= width) {
          not_nan_outside += !std::isnan(v);
          continue;
        }
        const float a = alone[static_cast<size_t>(r) * width + c];
        differ += std::memcmp(&a, &v, sizeof a) != 0;
      }
    }
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(not_nan_outside, 0);
  }
}

// Where the machine has AVX-512 the passes take 16 floats at a time; the values must be those
// of the 8-float code bit for bit, at widths with and without a remainder of 8 and of 1-7
// columns.
TEST(WindowedNcc, SixteenFloatPassesGiveTheEightFloatValues) {
  if (!WindowedNcc::MachineHasAvx512()) {
    GTEST_SKIP() << "this machine has no AVX-512: only the 8-float passes run here";
  }
  for (const int width : {64, 75, 131, 200}) {
    SCOPED_TRACE(width);
    const int height = 41;
    const cv::Mat I = BlurredNoiseImage(width, height, 6);
    const cv::Mat J = 0.8 * I + 0.1 + 0.05 * BlurredNoiseImage(width, height, 7);
    const size_t n = static_cast<size_t>(width) * height;
    std::vector<float> j(n), m(n);
    for (int row = 0; row < height; ++row) {
      for (int col = 0; col < width; ++col) {
        const bool valid = (row * 7 + col * 3) % 23 != 0 && col > 5;  // holes, an empty edge
        j[row * width + col] = valid ? J.at<float>(row, col) - 0.5f : 0.0f;
        m[row * width + col] = valid ? 1.0f : 0.0f;
      }
    }
    std::vector<float> wide(n), narrow(n);
    WindowedNcc sixteen(width, height, 3.0, 1e-4, 0.5, WindowedNcc::Vectors::kWidest);
    WindowedNcc eight(width, height, 3.0, 1e-4, 0.5, WindowedNcc::Vectors::k8Floats);
    sixteen.SetCamera(I);
    eight.SetCamera(I);
    const int64_t wide_defined = sixteen.Run(j.data(), m.data(), wide.data());
    EXPECT_EQ(wide_defined, eight.Run(j.data(), m.data(), narrow.data()));
    EXPECT_GT(wide_defined, static_cast<int64_t>(n / 2));
    EXPECT_EQ(std::memcmp(wide.data(), narrow.data(), n * sizeof(float)), 0);
  }
}

// The NCC flushes subnormals to zero while it runs, and leaves the thread's floating-point mode
// as it found it.
TEST(ScopedFlushSubnormals, FlushesInsideTheScopeOnly) {
  volatile float tiny = 1e-30f, factor = 1e-10f;  // their product is subnormal
  const float before = tiny * factor;
  EXPECT_GT(before, 0.0f);
  {
    const ScopedFlushSubnormals flush;
    const float inside = tiny * factor;
#if defined(__x86_64__) || defined(__i386__)
    EXPECT_EQ(inside, 0.0f);
#else
    EXPECT_EQ(inside, before);
#endif
  }
  EXPECT_EQ(tiny * factor, before);
  // Run keeps the mode too.
  WindowedNcc ncc(16, 16, 2.0, 1e-4, 0.5);
  ncc.SetCamera(BlurredNoiseImage(16, 16, 5));
  std::vector<float> j(256, 0.1f), m(256, 1.0f), out(256);
  ncc.Run(j.data(), m.data(), out.data());
  EXPECT_EQ(tiny * factor, before);
}

// ---- The reprojection ----

// The fast reprojection against the reference's on every pixel, over a plane that fills C's
// image, so that valid pixels reach the neighbour's last row and column, where a bilinear
// sample's second tap would lie outside the image.
TEST(CpuSweepSlab, ReprojectsLikeTheReference) {
  const SweepJob job = MakeSmallSweepJob(NoisyPyramidScene(), MakeFlatSquare(0.0, 50.0, 2));
  const PreparedSweep prep = PrepareSweep(job);
  CpuSweepSlab slab(job, prep);
  slab.Render(0);
  const View& view = prep.camera.view;
  SoftwareRasterizer camera_raster(view, prep.near, /*keep_world=*/true);
  RenderSoup(SweepFacets(job.mesh, FaceNormals(job.mesh), view.Center(), 0), &camera_raster);
  for (size_t j = 0; j < prep.neighbours.size(); ++j) {
    SCOPED_TRACE(j);
    const SweepCamera& n = prep.neighbours[j];
    SoftwareRasterizer shadow_map(n.view, prep.near, /*keep_world=*/false);
    RenderSoup(SweepFacets(job.mesh, FaceNormals(job.mesh), view.Center(), 0), &shadow_map);
    cv::Mat reprojected, mask;
    ReprojectNeighbour(camera_raster, n.view, n.image, shadow_map, job.options.occlusion_tolerance,
                       &reprojected, &mask);
    slab.Reproject(static_cast<int>(j));
    int both = 0, differ = 0;
    double worst = 0;
    for (int row = 0; row < mask.rows; ++row) {
      for (int col = 0; col < mask.cols; ++col) {
        const size_t i = static_cast<size_t>(row) * mask.cols + col;
        const bool fast = slab.valid()[i] > 0, reference = mask.at<uint8_t>(row, col) > 0;
        differ += fast != reference;
        if (!fast || !reference) continue;
        ++both;
        worst = std::max(worst,
                         std::abs(slab.reprojected()[i] + 0.5 - reprojected.at<float>(row, col)));
      }
    }
    EXPECT_GT(both, mask.rows * mask.cols / 4);
    EXPECT_LT(differ, both / 1000);  // float against double at the borders of validity
    EXPECT_LT(worst, 1e-3);
  }
}

// ---- End to end ----

// With the paper's rule and where winners must move (the default).
TEST(CpuSweep, PyramidFromAFlatSquareLikeTheReference) {
  SweepJob job = MakeSmallSweepJob(NoisyPyramidScene(), MakeFlatSquare(0.15, 1.3, 8));
  for (const bool must_move : {false, true}) {
    job.options.winners_must_move = must_move;
    const SweepResult ref = ReferenceSweepKernel().Run(job);
    const SweepResult cpu = CpuSweepKernel().Run(job);
    ASSERT_GT(ref.points.size(), 40u);
    ExpectSameWinners(ref, cpu, ref.stats.median_depth,
                      must_move ? "cpu, winners must move" : "cpu");
    EXPECT_EQ(cpu.stats.valid_hypotheses, ref.stats.valid_hypotheses);  // k = 0 counted
    EXPECT_EQ(cpu.stats.covered_pixels, ref.stats.covered_pixels);
    std::printf("  %s\n  reference: %s\n", cpu.stats.Summary().c_str(),
                ref.stats.Summary().c_str());
  }
}

TEST(CpuSweep, TrueMeshWithOcclusionAndDefaultWindow) {
  const PyramidScene& scene = NoisyPyramidScene();
  SweepJob job = MakeSmallSweepJob(scene, TruthWithOccluder(scene));
  job.options.num_offsets = 5;
  job.options.alpha = 0.03;
  job.options.gaussian_sigma_px = 8;
  job.options.winners_must_move = false;  // on the true mesh most winners are at k = 0
  // The strict rule (the default), two matching neighbours where both see the pixel and the
  // paper's (any one). Each one's candidates are a subset of the next one's, so it finds a point
  // in fewer tiles or as many.
  size_t points_before = 0;
  for (const auto& [required, strict] :
       {std::pair{2, true}, std::pair{2, false}, std::pair{1, false}}) {
    job.options.min_matching_neighbours = required;
    job.options.strict_support = strict;
    const SweepResult ref = ReferenceSweepKernel().Run(job);
    ASSERT_GT(ref.points.size(), 30u);
    ExpectSameWinners(
        ref, CpuSweepKernel().Run(job), ref.stats.median_depth,
        "cpu, occluder, " + std::to_string(required) + " matching" + (strict ? ", strict" : ""));
    EXPECT_LE(points_before, ref.points.size());
    points_before = ref.points.size();
  }
}

TEST(CpuSweep, ThreadsDoNotChangeTheResult) {
  const SweepJob job = MakeSmallSweepJob(NoisyPyramidScene(), MakeFlatSquare(0.12, 1.3, 4));
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const SweepResult one = CpuSweepKernel().Run(job);
  cv::setNumThreads(4);
  const SweepResult four = CpuSweepKernel().Run(job);
  cv::setNumThreads(threads);
  ASSERT_EQ(one.points.size(), four.points.size());
  ASSERT_GT(one.points.size(), 20u);
  for (size_t i = 0; i < one.points.size(); ++i) {
    EXPECT_EQ(one.points[i].position, four.points[i].position);
    EXPECT_EQ(one.points[i].ncc, four.points[i].ncc);
    EXPECT_EQ(one.points[i].cameras, four.points[i].cameras);
  }
  EXPECT_EQ(one.stats.valid_hypotheses, four.stats.valid_hypotheses);
}

TEST(CpuSweep, BlankTextureAndBadJobs) {
  PyramidSceneOptions blank;
  blank.texture_contrast = 0;
  const SweepResult none = CpuSweepKernel().Run(
      MakeSmallSweepJob(MakePyramidScene(blank), MakeFlatSquare(0.15, 1.3, 8)));
  EXPECT_EQ(none.points.size(), 0u);
  EXPECT_EQ(none.stats.valid_hypotheses, 0);
  EXPECT_GT(none.stats.covered_pixels, 0);
  SweepJob job = MakeSmallSweepJob(NoisyPyramidScene(), MakeFlatSquare(0.15, 1.3, 2));
  job.neighbours[1].image = cv::Mat(31, 40, CV_32F, cv::Scalar(0.5));
  CpuSweepKernel kernel;
  testing::ExpectInputError([&] { kernel.Run(job); }, {"image"});
}

}  // namespace
}  // namespace ms

namespace ms {
namespace {

// A winner's position must stay within the depths its facet spans, or the coordinator rejects
// the whole result (found on a 2,048-camera street: a point at 58.9 m where the job's mesh
// reached 45.1 m).
TEST(PixelRayOnFacet, StaysOnTheRayWithinTheFacetsDepths) {
  View view;  // at the origin, looking along +z
  view.intrinsics.width = view.intrinsics.height = 100;
  view.intrinsics.fx = view.intrinsics.fy = 100;
  view.intrinsics.cx = view.intrinsics.cy = 50;
  const Eigen::Vector2d pixel(50.5, 50.5);
  const Eigen::Vector3d ray = view.PixelRay(pixel);
  const auto on_ray = [&](const Eigen::Vector3d& x) { return x.normalized().dot(ray); };

  // Crossed well inside: the plain intersection.
  const std::array<Eigen::Vector3d, 3> flat = {Eigen::Vector3d(-1, -1, 3),
                                               Eigen::Vector3d(1, -1, 3), Eigen::Vector3d(0, 1, 3)};
  const Eigen::Vector3d inside = PixelRayOnFacet(view, pixel, flat, 0.01);
  EXPECT_NEAR(inside.z(), 3.0, 1e-12);
  EXPECT_NEAR(on_ray(inside), 1.0, 1e-12);

  // Grazing: the plane x = a z + b nearly holds the ray (x = 0.005 z); it crosses at z = 100,
  // the facet spans z = 2 ... 4.
  const double a = 0.005 - 1e-5, b = 1e-3;
  const std::array<Eigen::Vector3d, 3> grazing = {Eigen::Vector3d(2 * a + b, -1, 2),
                                                  Eigen::Vector3d(2 * a + b, 1, 2),
                                                  Eigen::Vector3d(4 * a + b, 0, 4)};
  const Eigen::Vector3d kept = PixelRayOnFacet(view, pixel, grazing, 0.01);
  EXPECT_GE(kept.z(), 2.0 - 1e-12);
  EXPECT_LE(kept.z(), 4.0 + 1e-12);
  EXPECT_NEAR(on_ray(kept), 1.0, 1e-12);
  Eigen::Vector2d projected;
  ASSERT_TRUE(view.Project(kept, &projected));
  EXPECT_LT((projected - pixel).norm(), 1e-6) << "the point left its pixel";

  // Parallel to the ray: no crossing at all; still a point of the pixel within the depths.
  const std::array<Eigen::Vector3d, 3> parallel = {
      Eigen::Vector3d(-1, 0.01, 2), Eigen::Vector3d(1, 0.01, 2), Eigen::Vector3d(0, 0.02, 4)};
  const Eigen::Vector3d along = PixelRayOnFacet(view, pixel, parallel, 0.01);
  EXPECT_TRUE(along.allFinite());
  EXPECT_GE(along.z(), 2.0 - 1e-12);
  EXPECT_LE(along.z(), 4.0 + 1e-12);
}

}  // namespace
}  // namespace ms
