#include "manifold/ray_index.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>

namespace ms {
namespace {

// Brute force: does the segment a-b meet the box? (dense sampling is enough for a superset
// check because we only assert the index never misses a ray that clearly hits.)
bool SegmentHitsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& lo,
                    const Eigen::Vector3d& hi) {
  for (int i = 0; i <= 2000; ++i) {
    const Eigen::Vector3d x = a + (b - a) * (i / 2000.0);
    if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) return true;
  }
  return false;
}

TEST(RayIndex, NeverMissesARayThatCrossesTheBox) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<RayIndex::Camera> cameras;
  for (int c = 0; c < 4; ++c) {
    RayIndex::Camera cam;
    const double angle = c * 1.3;
    cam.center = Eigen::Vector3d(4 * std::cos(angle), 4 * std::sin(angle), 0.5 * c);
    // Look at the origin.
    const Eigen::Vector3d z = -cam.center.normalized();
    const Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(z).normalized();
    const Eigen::Vector3d y = z.cross(x);
    cam.R.row(0) = x;
    cam.R.row(1) = y;
    cam.R.row(2) = z;
    cam.u_min = cam.v_min = -0.4;
    cam.u_max = cam.v_max = 0.4;  // some rays fall outside: overflow
    cameras.push_back(cam);
  }
  RayIndex index(cameras, 16);
  std::vector<Eigen::Vector3d> points;
  std::vector<RayRef> all;
  for (int i = 0; i < 600; ++i) {
    // Half filed in buckets (flushed), half still pending: queries must see both.
    if (i == 300) index.Flush();
    points.emplace_back(u(rng), u(rng), u(rng));
    for (int c = 0; c < 4; ++c) {
      if ((i + c) % 2 == 0) {
        const int32_t id = index.Add(c, i, points.back());
        EXPECT_EQ(id, static_cast<int32_t>(all.size())) << "ids number rays in order";
        all.push_back({c, i, id});
      }
    }
  }
  EXPECT_EQ(index.size(), all.size());
  RayIndex flushed = index;
  flushed.Flush();
  for (int q = 0; q < 40; ++q) {
    const Eigen::Vector3d center(u(rng), u(rng), u(rng));
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.05 + 0.2 * std::abs(u(rng)));
    const Eigen::Vector3d lo = center - half, hi = center + half;
    std::vector<RayRef> found, found_flushed;
    index.Query(lo, hi, &found);
    std::sort(found.begin(), found.end());
    flushed.Query(lo, hi, &found_flushed);
    std::sort(found_flushed.begin(), found_flushed.end());
    EXPECT_EQ(found, found_flushed) << "pending and filed rays answer differently";
    int hits = 0;
    for (const RayRef& ray : found) {
      ASSERT_GE(ray.id, 0);
      ASSERT_LT(ray.id, static_cast<int32_t>(all.size()));
      EXPECT_TRUE(all[ray.id] == ray) << "a query answers a ray with another ray's id";
    }
    for (const RayRef& ray : all) {
      if (SegmentHitsBox(cameras[ray.camera].center, points[ray.point], lo, hi)) {
        ++hits;
        EXPECT_TRUE(std::binary_search(found.begin(), found.end(), ray))
            << "missed camera " << ray.camera << " point " << ray.point;
      }
    }
    // Conservative but selective: far fewer candidates than rays.
    EXPECT_LT(found.size(), all.size());
    EXPECT_GE(static_cast<int>(found.size()), hits);
  }
}

// An 8x8 grid over [-1, 1]^2 of x/z, y/z for each.
RayIndex TwoCamerasAtTheOriginLookingUpZ() {
  RayIndex::Camera cam;
  cam.R.setIdentity();
  cam.center.setZero();
  return RayIndex({cam, cam}, 8);
}

TEST(RayIndex, VisitsEveryRayOnceCameraByCameraInDirectionOrder) {
  RayIndex index = TwoCamerasAtTheOriginLookingUpZ();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2, 2);
  std::vector<RayRef> added;
  for (int i = 0; i < 400; ++i) {
    if (i == 250) index.Flush();  // some filed, some pending
    // Some behind the camera or outside the grid: the overflow list.
    const Eigen::Vector3d x(u(rng), u(rng), i % 7 == 0 ? -1.0 : 1.0 + std::abs(u(rng)));
    const int32_t camera = i % 2;
    added.push_back({camera, i, index.Add(camera, i, x)});
  }
  std::vector<RayRef> visited;
  index.ForEachInDirectionOrder([&](const RayRef& ray) { visited.push_back(ray); });
  ASSERT_EQ(visited.size(), added.size());
  std::vector<int> seen(added.size(), 0);
  for (size_t k = 0; k < visited.size(); ++k) {
    const RayRef& ray = visited[k];
    ASSERT_GE(ray.id, 0);
    ASSERT_LT(ray.id, static_cast<int32_t>(added.size()));
    EXPECT_TRUE(added[ray.id] == ray);
    ++seen[ray.id];
    if (k > 0) {
      EXPECT_LE(visited[k - 1].camera, ray.camera) << "cameras one after another";
    }
  }
  for (int count : seen) EXPECT_EQ(count, 1);
}

// The manifold keeps no camera list per point: the index answers whether a ray is there.
TEST(RayIndex, ContainsAnswersForFiledPendingAndOverflowRays) {
  RayIndex index = TwoCamerasAtTheOriginLookingUpZ();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2, 2);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 300; ++i) {
    if (i == 200) index.Flush();  // 0..199 filed (the grid grows), the rest pending
    // Every 7th behind the camera, and |x/z| up to 2 past the grid's [-1, 1]: the overflow.
    points.emplace_back(u(rng), u(rng), i % 7 == 0 ? -1.0 : 1.0 + std::abs(u(rng)));
    if (i % 3 != 0) index.Add(0, i, points.back());
    if (i % 2 == 0) index.Add(1, i, points.back());
  }
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < 300; ++i) {
      EXPECT_EQ(index.Contains(0, i, points[i]), i % 3 != 0) << "camera 0, point " << i;
      EXPECT_EQ(index.Contains(1, i, points[i]), i % 2 == 0) << "camera 1, point " << i;
    }
    // Another point at the same place is another ray.
    EXPECT_FALSE(index.Contains(0, 1000, points[1]));
    index.Flush();  // and again with every ray filed
  }
}

// Brute-force reference for the two tests below: the rays whose segment clearly meets the box.
std::vector<RayRef> RaysHitting(const std::vector<RayIndex::Camera>& cameras,
                                const std::vector<Eigen::Vector3d>& points,
                                const std::vector<RayRef>& rays, const Eigen::Vector3d& lo,
                                const Eigen::Vector3d& hi) {
  std::vector<RayRef> hits;
  for (const RayRef& ray : rays) {
    if (SegmentHitsBox(cameras[ray.camera].center, points[ray.point], lo, hi)) hits.push_back(ray);
  }
  return hits;
}

TEST(RayIndex, AGridThatGrowsWithItsRaysStillFindsEveryRay) {
  // One camera, rays added in batches: the grid starts at one bucket and doubles its side as
  // the rays come (kRaysPerBucket each), refiling what it holds each time.
  RayIndex::Camera cam;
  cam.R.setIdentity();
  cam.center.setZero();
  RayIndex index({cam}, 64);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.9, 0.9), depth(1, 3);
  std::vector<Eigen::Vector3d> points;
  std::vector<RayRef> rays;
  size_t memory_before = index.MemoryBytes();
  for (int batch = 0; batch < 6; ++batch) {
    const int n = 20 << batch;  // 20 ... 640: the side grows 2 -> 16 along the way
    for (int i = 0; i < n; ++i) {
      const double z = depth(rng);
      points.emplace_back(u(rng) * z, u(rng) * z, z);
      const int32_t point = static_cast<int32_t>(points.size()) - 1;
      rays.push_back({0, point, index.Add(0, point, points.back())});
    }
    index.Flush();
    EXPECT_GT(index.MemoryBytes(), memory_before);
    memory_before = index.MemoryBytes();
    for (int q = 0; q < 30; ++q) {
      const Eigen::Vector3d center(u(rng), u(rng), depth(rng));
      const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.02 + 0.1 * std::abs(u(rng)));
      std::vector<RayRef> found;
      index.Query(center - half, center + half, &found);
      std::sort(found.begin(), found.end());
      for (const RayRef& hit : RaysHitting({cam}, points, rays, center - half, center + half)) {
        EXPECT_TRUE(std::binary_search(found.begin(), found.end(), hit))
            << "batch " << batch << ": missed point " << hit.point;
      }
      EXPECT_LT(found.size(), rays.size() / 2 + 5) << "the grid selects, batch " << batch;
    }
  }
  // A full-size grid would be 64 x 64 buckets; 1,260 rays need 16 x 16.
  EXPECT_LT(index.MemoryBytes(), rays.size() * 24 + 17 * 17 * 4 + 4096);
}

TEST(RayIndex, AQuerySkipsCamerasWhoseRaysAreElsewhere) {
  // Two cameras far apart along a street, each seeing its own block of points.
  std::vector<RayIndex::Camera> cameras(2);
  for (int c = 0; c < 2; ++c) {
    cameras[c].R.setIdentity();
    cameras[c].center = Eigen::Vector3d(100.0 * c, 0, 0);
  }
  RayIndex index(cameras, 16);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Vector3d> points;
  std::vector<RayRef> rays;
  for (int i = 0; i < 400; ++i) {
    const int32_t camera = i % 2;
    points.push_back(cameras[camera].center + Eigen::Vector3d(u(rng), u(rng), 2 + u(rng)));
    rays.push_back({camera, i, index.Add(camera, i, points.back())});
  }
  index.Flush();
  // A box at camera 0's points: only camera 0's rays come back, every hitting one among them.
  const Eigen::Vector3d lo(-0.3, -0.3, 1.6), hi(0.3, 0.3, 2.4);
  std::vector<RayRef> found;
  index.Query(lo, hi, &found);
  ASSERT_FALSE(found.empty());
  for (const RayRef& ray : found) EXPECT_EQ(ray.camera, 0);
  std::sort(found.begin(), found.end());
  for (const RayRef& hit : RaysHitting(cameras, points, rays, lo, hi)) {
    EXPECT_TRUE(std::binary_search(found.begin(), found.end(), hit));
  }
  // A box between the two blocks that reaches behind both cameras' image planes (z <= 0):
  // projected, it could hold any ray of either camera, so only the cull by the cameras' ray
  // boxes keeps the answer empty (without it, the rays of both cameras come back).
  found.clear();
  index.Query(Eigen::Vector3d(40, -1, -1), Eigen::Vector3d(60, 1, 1), &found);
  EXPECT_TRUE(found.empty()) << found.size() << " rays";
}

}  // namespace
}  // namespace ms
