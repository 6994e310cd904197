#include "mesh/ray_caster.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <random>

namespace ms {
namespace {

// Brute force reference: nearest hit over all faces.
bool BruteForce(const Mesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max,
                double* t_best) {
  bool found = false;
  *t_best = t_max;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d a = mesh.vertices[f[0]], b = mesh.vertices[f[1]], c = mesh.vertices[f[2]];
    Eigen::Matrix3d m;
    m << b - a, c - a, -d;
    if (std::abs(m.determinant()) < 1e-14) continue;
    const Eigen::Vector3d x = m.fullPivLu().solve(o - a);  // a + u e1 + v e2 = o + t d
    if (x[0] < 0 || x[1] < 0 || x[0] + x[1] > 1 || x[2] <= 0 || x[2] >= *t_best) continue;
    *t_best = x[2];
    found = true;
  }
  return found;
}

Mesh RandomTriangles(int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> pos(-5, 5), offset(-0.8, 0.8);
  Mesh mesh;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d c(pos(rng), pos(rng), pos(rng));
    for (int k = 0; k < 3; ++k) {
      mesh.vertices.push_back(c + Eigen::Vector3d(offset(rng), offset(rng), offset(rng)));
    }
    mesh.faces.push_back({3 * i, 3 * i + 1, 3 * i + 2});
  }
  return mesh;
}

TEST(RayCaster, MatchesBruteForceOnRandomTriangles) {
  const Mesh mesh = RandomTriangles(500, 7);
  const RayCaster caster(mesh);
  EXPECT_EQ(caster.num_faces(), 500u);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> pos(-6, 6);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d o(pos(rng), pos(rng), pos(rng));
    const Eigen::Vector3d d = Eigen::Vector3d(pos(rng), pos(rng), pos(rng)).normalized();
    double expected_t = 0;
    const bool expected = BruteForce(mesh, o, d, 100, &expected_t);
    RayCaster::Hit hit;
    const bool got = caster.Intersect(o, d, 0, 100, &hit);
    ASSERT_EQ(got, expected) << "ray " << i;
    if (got) {
      ++hits;
      EXPECT_NEAR(hit.t, expected_t, 1e-9);
      const Eigen::Vector3d p = o + hit.t * d;
      // The reported face contains the hit point.
      const auto& f = mesh.faces[hit.face];
      const Eigen::Vector3d a = mesh.vertices[f[0]], b = mesh.vertices[f[1]],
                            c = mesh.vertices[f[2]];
      EXPECT_NEAR(std::abs((b - a).cross(c - a).normalized().dot(p - a)), 0, 1e-9);
    }
  }
  EXPECT_GT(hits, 200);
}

TEST(RayCaster, OccludedIgnoresTheTargetsOwnSurface) {
  Mesh mesh;
  mesh.vertices = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0},
                   {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}};  // a square at z=0, a triangle at z=1
  const RayCaster caster(mesh);
  const Eigen::Vector3d target(-0.5, 0.5, 0);  // on the square, not under the triangle
  EXPECT_FALSE(caster.Occluded({-0.5, 0.5, 3}, target, 1e-6));
  const Eigen::Vector3d under(0.5, -0.5, 0);  // under the triangle at z=1
  EXPECT_TRUE(caster.Occluded({0.5, -0.5, 3}, under, 1e-6));
  EXPECT_FALSE(caster.Occluded({0.5, -0.5, 0.5}, under, 1e-6));  // camera below the triangle
  RayCaster::Hit hit;
  ASSERT_TRUE(caster.Intersect({0.5, -0.5, 3}, {0, 0, -1}, 0, 10, &hit));
  EXPECT_NEAR(hit.t, 2, 1e-12);
  EXPECT_EQ(hit.face, 2);
  EXPECT_FALSE(caster.Intersect({0.5, -0.5, 3}, {0, 0, 1}, 0, 10, &hit));
}

TEST(RayCaster, EmptyAndDegenerateMeshes) {
  const RayCaster empty{Mesh{}};
  EXPECT_FALSE(empty.Occluded({0, 0, 0}, {1, 1, 1}, 0));
  Mesh flat;
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.faces = {{0, 1, 2}};
  const RayCaster degenerate(flat);
  EXPECT_EQ(degenerate.num_faces(), 0u);
}

}  // namespace
}  // namespace ms
