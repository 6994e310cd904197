#include "coordinator/insertion_batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace ms {
namespace {

wire::SweepPoint* AddPoint(wire::Result* result, double x, float px, float py,
                           std::vector<int32_t> cameras) {
  wire::SweepPoint* p = result->add_points();
  p->set_x(x);
  p->set_y(0.5 * x);
  p->set_z(1);
  p->set_pixel_x(px);
  p->set_pixel_y(py);
  for (int32_t c : cameras) p->add_cameras(c);
  return p;
}

// Jobs 0..3, camera c's points at a few pixels, some of them tied on pixel.
std::vector<std::pair<uint64_t, std::vector<FoundPoint>>> Results() {
  std::vector<std::pair<uint64_t, std::vector<FoundPoint>>> results;
  for (int32_t camera = 0; camera < 4; ++camera) {
    wire::Result result;
    AddPoint(&result, camera + 0.1, 10, 20, {camera, (camera + 1) % 4});
    AddPoint(&result, camera + 0.2, 5, 20, {camera});
    AddPoint(&result, camera + 0.3, 5, 20, {camera, (camera + 3) % 4});  // same pixel
    AddPoint(&result, camera + 0.4, 90, 3, {camera, (camera + 2) % 4});
    std::vector<FoundPoint> points;
    EXPECT_EQ(ValidateResultPoints(result, camera, 4, &points), "");
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

TEST(InsertionBatch, ResultsThatDoNotFitTheirJobAreRefusedWithTheReason) {
  std::vector<FoundPoint> points;
  wire::Result wrong_first;
  AddPoint(&wrong_first, 1, 1, 1, {1, 2});
  EXPECT_EQ(ValidateResultPoints(wrong_first, 2, 4, &points),
            "point 0 does not list camera 2 first");
  wire::Result twice;
  AddPoint(&twice, 1, 1, 1, {2, 3, 3});
  EXPECT_EQ(ValidateResultPoints(twice, 2, 4, &points),
            "point 0 lists camera 3 (twice, or not in the scene)");
  wire::Result outside;
  AddPoint(&outside, 1, 1, 1, {2, 4});
  EXPECT_EQ(ValidateResultPoints(outside, 2, 4, &points),
            "point 0 lists camera 4 (twice, or not in the scene)");
  wire::Result nan;
  AddPoint(&nan, std::nan(""), 1, 1, {2});
  EXPECT_EQ(ValidateResultPoints(nan, 2, 4, &points), "point 0 is not finite");
}

}  // namespace
}  // namespace ms
