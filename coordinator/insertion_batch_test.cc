#include "coordinator/insertion_batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "testing/test_job.h"

namespace ms {
namespace {

FoundPoint Found(int32_t camera, double x, float px, float py, std::vector<int32_t> cameras) {
  FoundPoint f;
  f.camera = camera;
  f.position = {x, 0.5 * x, 1};
  f.pixel_x = px;
  f.pixel_y = py;
  f.cameras = std::move(cameras);
  return f;
}

// Jobs 0..3, camera c's points at a few pixels, some of them tied on pixel.
std::vector<std::pair<uint64_t, std::vector<FoundPoint>>> Results() {
  std::vector<std::pair<uint64_t, std::vector<FoundPoint>>> results;
  for (int32_t camera = 0; camera < 4; ++camera) {
    std::vector<FoundPoint> points = {
        Found(camera, camera + 0.1, 10, 20, {camera, (camera + 1) % 4}),
        Found(camera, camera + 0.2, 5, 20, {camera}),
        Found(camera, camera + 0.3, 5, 20, {camera, (camera + 3) % 4}),  // same pixel
        Found(camera, camera + 0.4, 90, 3, {camera, (camera + 2) % 4})};
    results.emplace_back(uint64_t{1} << 32 | static_cast<uint64_t>(camera), std::move(points));
  }
  return results;
}

std::vector<std::string> Describe(const std::vector<RayPoint>& batch) {
  std::vector<std::string> lines;
  for (const RayPoint& p : batch) {
    std::string line = std::to_string(p.position.x());
    for (int32_t c : p.cameras) line += " " + std::to_string(c);
    lines.push_back(line);
  }
  return lines;
}

TEST(InsertionBatch, IsSortedByCameraThenPixelRowThenColumn) {
  InsertionBatch batch;
  for (auto& [id, points] : Results()) batch.Add(id, points);
  const std::vector<std::string> lines = Describe(batch.Sorted());
  ASSERT_EQ(lines.size(), 16u);
  // Camera 0: row 3 first, then row 20 at x = 5 (two points, by position), then x = 10.
  EXPECT_EQ(lines[0], "0.400000 0 2");
  EXPECT_EQ(lines[1], "0.200000 0");
  EXPECT_EQ(lines[2], "0.300000 0 3");
  EXPECT_EQ(lines[3], "0.100000 0 1");
  EXPECT_EQ(lines[4], "1.400000 1 3");
}

// The coordinator inserts runs of jobs in camera order while the sweep goes on: the parts, one
// after the other, must be the whole sorted batch.
TEST(InsertionBatch, PartsByConsecutiveJobsMakeTheSortedBatch) {
  InsertionBatch batch;
  std::vector<uint64_t> ids;
  for (auto& [id, points] : Results()) {
    batch.Add(id, points);
    ids.push_back(id);
  }
  EXPECT_TRUE(batch.Has(ids[2]));
  EXPECT_FALSE(batch.Has(ids[3] + 1));
  std::vector<std::string> parts;
  for (const std::vector<uint64_t>& run :
       {std::vector<uint64_t>{ids[0]}, std::vector<uint64_t>{ids[1], ids[2]},
        std::vector<uint64_t>{}, std::vector<uint64_t>{ids[3]}}) {
    for (const std::string& line : Describe(batch.SortedOf(run))) parts.push_back(line);
  }
  EXPECT_EQ(parts, Describe(batch.Sorted()));
}

TEST(InsertionBatch, ArrivalOrderAndDuplicateResultsDoNotChangeTheBatch) {
  const auto results = Results();
  InsertionBatch reference;
  for (const auto& [id, points] : results) reference.Add(id, points);
  const std::vector<std::string> expected = Describe(reference.Sorted());
  std::mt19937 random(7);
  for (int trial = 0; trial < 20; ++trial) {
    auto shuffled = results;
    std::shuffle(shuffled.begin(), shuffled.end(), random);
    InsertionBatch batch;
    for (const auto& [id, points] : shuffled) {
      EXPECT_TRUE(batch.Add(id, points));
      // A duplicate delivery of the same job, even with other points, is ignored.
      auto other = points;
      other.pop_back();
      EXPECT_FALSE(batch.Add(id, other));
      EXPECT_FALSE(batch.AddEmpty(id));
    }
    EXPECT_EQ(batch.num_points(), 16);
    EXPECT_EQ(Describe(batch.Sorted()), expected) << "trial " << trial;
  }
}

TEST(InsertionBatch, ARefusedJobCountsAsAJobWithoutPoints) {
  InsertionBatch batch;
  EXPECT_TRUE(batch.AddEmpty(5));
  EXPECT_FALSE(batch.Add(5, Results()[0].second));
  EXPECT_EQ(batch.num_jobs(), 1u);
  EXPECT_TRUE(batch.Sorted().empty());
}

wire::SweepPoint* AddPoint(wire::Result* result, const Eigen::Vector3d& x,
                           std::vector<int32_t> cameras) {
  wire::SweepPoint* p = result->add_points();
  p->set_x(x.x());
  p->set_y(x.y());
  p->set_z(x.z());
  p->set_pixel_x(static_cast<float>(500 * x.x() / x.z() + 320));
  p->set_pixel_y(static_cast<float>(500 * x.y() / x.z() + 240));
  for (int32_t c : cameras) p->add_cameras(c);
  return p;
}

TEST(InsertionBatch, ResultsThatDoNotFitTheirJobAreRefusedWithTheReason) {
  const JobBounds job = JobBoundsFromWire(testing::MakeSmallTestJob());
  EXPECT_EQ(job.cameras, (std::vector<int32_t>{2, 0, 3}));
  EXPECT_NEAR(job.min_depth, 4.1, 1e-12);
  EXPECT_NEAR(job.max_depth, 5.9, 1e-12);
  std::vector<FoundPoint> points;
  wire::Result good;
  AddPoint(&good, {0.3, -0.2, 5.4}, {2, 3});
  AddPoint(&good, {-1.1, 0.8, 4.2}, {2});
  EXPECT_EQ(ValidateResultPoints(good, job, &points), "");
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0].cameras, (std::vector<int32_t>{2, 3}));
  const auto problem = [&](const Eigen::Vector3d& x, std::vector<int32_t> cameras,
                           float shift_px = 0) {
    wire::Result result;
    AddPoint(&result, {0.3, -0.2, 5.4}, {2});  // a good one first: the result is dropped whole
    wire::SweepPoint* p = AddPoint(&result, x, std::move(cameras));
    p->set_pixel_x(p->pixel_x() + shift_px);
    std::vector<FoundPoint> out;
    return ValidateResultPoints(result, job, &out);
  };
  EXPECT_EQ(problem({0, 0, 5}, {1, 2}), "point 1 does not list camera 2 first");
  EXPECT_EQ(problem({0, 0, 5}, {2, 3, 3}),
            "point 1 lists camera 3 (twice, or not one of the job's)");
  EXPECT_EQ(problem({0, 0, 5}, {2, 1}), "point 1 lists camera 1 (twice, or not one of the job's)");
  EXPECT_EQ(problem({std::nan(""), 0, 5}, {2}), "point 1 is not finite");
  // Off its pixel's ray (a rogue point anywhere in the box), out of depth range, outside the
  // image.
  EXPECT_NE(problem({0, 0, 5}, {2}, 3).find("projects to (320.00, 240.00) in camera 2, not to"),
            std::string::npos);
  EXPECT_NE(problem({0, 0, 7}, {2}).find("outside the swept range [4.1, 5.9]"), std::string::npos);
  EXPECT_NE(problem({0, 0, -5}, {2}).find("outside the swept range"), std::string::npos);
  EXPECT_NE(problem({4, 0, 5}, {2}).find("outside camera 2's 640x480 image"), std::string::npos);
  // Within the tolerance of the pixel: accepted.
  EXPECT_EQ(problem({0, 0, 5}, {2}, 0.4f), "");
}

}  // namespace
}  // namespace ms
