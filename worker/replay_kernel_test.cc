// The replay kernel hands back a recorded run's points as the sweep reported them: the same
// positions and cameras, and the pixel the sweep found each at, so the coordinator sorts and
// inserts exactly the recorded batch.
#include "worker/replay_kernel.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace ms {
namespace {

View MakeView(double x) {
  View view;
  view.intrinsics.width = 3200;
  view.intrinsics.height = 2400;
  view.intrinsics.fx = view.intrinsics.fy = 2800;
  view.intrinsics.cx = 1600;
  view.intrinsics.cy = 1200;
  view.SetCenter({x, 0, -10});
  return view;
}

// Where the sweep puts a point found at swept pixel (col, row) of a level-1 job: on the ray
// through the pixel's centre, at depth `depth`.
RayPoint FoundAt(const View& view, int col, int row, double depth, std::vector<int32_t> cameras) {
  const Eigen::Vector2d centre((col + 0.5) * 2, (row + 0.5) * 2);
  const Eigen::Vector3d ray = view.PixelRay(centre);
  RayPoint p;
  p.position = view.Center() + ray * (depth / ray.dot(view.Axis()));
  p.cameras = std::move(cameras);
  return p;
}

class ReplayKernelTest : public ::testing::Test {
 protected:
  void SetUp() override {
    views_ = {MakeView(0), MakeView(1), MakeView(2)};
    batches_.resize(2);
    batches_[0] = {FoundAt(views_[0], 10, 20, 9.5, {0, 1}),
                   FoundAt(views_[1], 799, 599, 10.25, {1, 0, 2}),
                   FoundAt(views_[0], 1599, 0, 11, {0, 1, 2})};
    batches_[1] = {FoundAt(views_[0], 0, 1199, 8, {0, 1})};
    options_.run = "recorded/run.h5";
    options_.delay_s = 0;
  }

  SweepJob Job(int32_t camera, uint32_t iteration) const {
    SweepJob job;
    job.camera.id = camera;
    job.camera.view = views_[camera];
    job.iteration = iteration;
    job.options.max_image_dimension = 1600;  // level 1: pixels are pairs of full-size pixels
    for (int32_t n = 0; n < static_cast<int32_t>(views_.size()); ++n) {
      if (n != camera) job.neighbours.push_back({n, views_[n], {}});
    }
    return job;
  }

  std::vector<View> views_;
  std::vector<std::vector<RayPoint>> batches_;
  ReplayKernelOptions options_;
};

TEST_F(ReplayKernelTest, HandsBackTheCamerasRecordedPointsAtTheSweptPixelsCentres) {
  ReplayKernel kernel(options_, views_, batches_);
  EXPECT_FALSE(kernel.NeedsImages());
  EXPECT_EQ(kernel.recorded_iterations(), 2);
  const SweepResult result = kernel.Run(Job(0, 1));
  ASSERT_EQ(result.points.size(), 2u);
  EXPECT_EQ(result.stats.image_width, 1600);
  EXPECT_EQ(result.stats.pyramid_level, 1);
  EXPECT_EQ(result.points[0].position, batches_[0][0].position);
  EXPECT_EQ(result.points[0].cameras, (std::vector<int32_t>{0, 1}));
  // Bit for bit the pixel MakeSweepPoint wrote: the coordinator sorts the batch by it.
  EXPECT_EQ(result.points[0].pixel.x(), static_cast<float>(10.5 / 0.5));
  EXPECT_EQ(result.points[0].pixel.y(), static_cast<float>(20.5 / 0.5));
  EXPECT_EQ(result.points[1].pixel.x(), static_cast<float>(1599.5 / 0.5));
  EXPECT_EQ(result.points[1].pixel.y(), static_cast<float>(0.5 / 0.5));
  EXPECT_EQ(result.points[1].cameras, (std::vector<int32_t>{0, 1, 2}));
  EXPECT_FLOAT_EQ(result.points[1].ncc, 0.98f);

  const SweepResult other = kernel.Run(Job(1, 1));
  ASSERT_EQ(other.points.size(), 1u);
  EXPECT_EQ(other.points[0].pixel.x(), static_cast<float>(799.5 / 0.5));
  EXPECT_EQ(other.points[0].cameras, (std::vector<int32_t>{1, 0, 2}));
  EXPECT_TRUE(kernel.Run(Job(2, 1)).points.empty());  // camera 2 found nothing
  EXPECT_EQ(kernel.Run(Job(0, 2)).points.size(), 1u);
}

// The coordinator appends witness cameras to a point (coordinator/witness_cameras.h) before it
// records the batch; a sweep returns only the job's cameras, and so does the replay.
TEST_F(ReplayKernelTest, LeavesOutTheWitnessesTheCoordinatorAdded) {
  batches_[0] = {FoundAt(views_[0], 10, 20, 9.5, {0, 1, 2})};
  ReplayKernel kernel(options_, views_, batches_);
  SweepJob job = Job(0, 1);
  job.neighbours.pop_back();  // camera 2 is no neighbour of this job: a witness
  const SweepResult result = kernel.Run(job);
  ASSERT_EQ(result.points.size(), 1u);
  EXPECT_EQ(result.points[0].cameras, (std::vector<int32_t>{0, 1}));
}

TEST_F(ReplayKernelTest, TakesTheDelayOfTheSweepItStandsFor) {
  options_.delay_s = 0.05;
  ReplayKernel kernel(options_, views_, batches_);
  EXPECT_GE(kernel.Run(Job(0, 1)).stats.total_s, 0.05);
}

TEST_F(ReplayKernelTest, RefusesAnIterationTheRunDidNotRecord) {
  ReplayKernel kernel(options_, views_, batches_);
  try {
    kernel.Run(Job(0, 3));
    FAIL() << "iteration 3 was replayed";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "recorded/run.h5 recorded 2 iterations; the job is of iteration 3");
  }
  EXPECT_THROW(kernel.Run(Job(0, 0)), InputError);
}

TEST_F(ReplayKernelTest, RefusesACameraOfAnotherScene) {
  ReplayKernel kernel(options_, views_, batches_);
  SweepJob job = Job(1, 1);
  job.camera.view.SetCenter({1, 0.001, -10});
  EXPECT_THROW(kernel.Run(job), InputError);
  job = Job(1, 1);
  job.camera.id = 3;
  EXPECT_THROW(kernel.Run(job), InputError);
}

TEST_F(ReplayKernelTest, NeedsARunToReplay) {
  options_.run.clear();
  EXPECT_THROW(ReplayKernel(options_, views_, batches_), InputError);
  options_.run = "recorded/run.h5";
  batches_[1][0].cameras.clear();
  EXPECT_THROW(ReplayKernel(options_, views_, batches_), InputError);
}

}  // namespace
}  // namespace ms
