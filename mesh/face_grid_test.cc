#include "mesh/face_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "mesh/float_robustness.h"
#include "testing/test_meshes.h"

namespace ms {
namespace {

// An icosahedron subdivided into small faces (each split in four, `levels` times), with a
// second, smaller one inside it that touches nothing, and one huge face across both (oversized
// for the grid).
Mesh FineMesh(int levels) {
  Mesh mesh = test_meshes::Icosahedron();
  for (int l = 0; l < levels; ++l) {
    Mesh finer;
    finer.vertices = mesh.vertices;
    for (const auto& t : mesh.faces) {
      int32_t m[3];
      for (int k = 0; k < 3; ++k) {
        m[k] = static_cast<int32_t>(finer.vertices.size());
        finer.vertices.push_back(
            (0.5 * (mesh.vertices[t[k]] + mesh.vertices[t[(k + 1) % 3]])).normalized());
      }
      finer.faces.push_back({t[0], m[0], m[2]});
      finer.faces.push_back({m[0], t[1], m[1]});
      finer.faces.push_back({m[2], m[1], t[2]});
      finer.faces.push_back({m[0], m[1], m[2]});
    }
    mesh = finer;
  }
  Mesh inner = test_meshes::Icosahedron();
  for (Eigen::Vector3d& v : inner.vertices) v *= 0.97;
  mesh = test_meshes::Append(mesh, inner);
  const auto n = static_cast<int32_t>(mesh.vertices.size());
  mesh.vertices.push_back({-50, -50, 0.3});
  mesh.vertices.push_back({50, -50, 0.3});
  mesh.vertices.push_back({0, 50, 0.3});
  mesh.faces.push_back({n, n + 1, n + 2});
  return mesh;
}

std::vector<uint8_t> RandomFocus(size_t faces, double share, uint32_t seed) {
  std::mt19937 random(seed);
  std::bernoulli_distribution pick(share);
  std::vector<uint8_t> focus(faces);
  for (auto& f : focus) f = pick(random);
  return focus;
}

// Every pair a box search over the whole mesh finds for the flagged faces is among the grid's.
void ExpectSuperset(const Mesh& mesh, const FaceGrid& grid, const std::vector<uint8_t>& focus,
                    double tolerance) {
  const PairCandidates searched = FindPairCandidates(mesh, mesh.vertices, tolerance, focus);
  const PairCandidates grid_pairs = grid.Candidates(mesh, focus);
  ASSERT_FALSE(searched.faces.empty());
  for (const auto& pair : searched.faces) {
    EXPECT_TRUE(std::binary_search(grid_pairs.faces.begin(), grid_pairs.faces.end(), pair))
        << "faces " << pair[0] << ", " << pair[1];
  }
  for (const auto& pair : searched.vertices) {
    EXPECT_TRUE(std::binary_search(grid_pairs.vertices.begin(), grid_pairs.vertices.end(), pair))
        << "vertices " << pair[0] << ", " << pair[1];
  }
}

TEST(FaceGrid, HoldsEveryPairABoxSearchFinds) {
  const Mesh mesh = FineMesh(3);
  const double tolerance = 0.02;  // wide: the inner icosahedron's faces come within it
  const FaceGrid grid(mesh, tolerance);
  ASSERT_EQ(grid.num_faces(), mesh.faces.size());
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    ExpectSuperset(mesh, grid, RandomFocus(mesh.faces.size(), 0.05, seed), tolerance);
  }
  // The huge face meets every other face's box: a focus on it alone lists them all.
  std::vector<uint8_t> huge(mesh.faces.size(), 0);
  huge.back() = 1;
  ExpectSuperset(mesh, grid, huge, tolerance);
}

// After faces move, appear and are renumbered, as remeshing does to them, the grid still holds
// every pair, and as few as a grid built anew.
TEST(FaceGrid, FollowsFacesThatChange) {
  Mesh mesh = FineMesh(3);
  const double tolerance = 0.01;
  FaceGrid grid(mesh, tolerance);
  // Move a patch of vertices outwards, append a copy of a few faces, drop every seventh face.
  for (size_t v = 0; v < 40; ++v) mesh.vertices[v] *= 1.05;
  std::vector<uint8_t> moved(mesh.faces.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int32_t v : mesh.faces[f]) moved[f] = moved[f] || v < 40;
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (moved[f]) grid.Update(mesh, static_cast<int32_t>(f));
  }
  for (int k = 0; k < 10; ++k) {
    auto t = mesh.faces[static_cast<size_t>(k) * 13];
    std::swap(t[1], t[2]);
    mesh.faces.push_back(t);
    grid.Update(mesh, static_cast<int32_t>(mesh.faces.size() - 1));
  }
  std::vector<int64_t> new_index(mesh.faces.size(), -1);
  Mesh kept;
  kept.vertices = mesh.vertices;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (f % 7 == 3) continue;
    new_index[f] = static_cast<int64_t>(kept.faces.size());
    kept.faces.push_back(mesh.faces[f]);
  }
  grid.Renumber(new_index);
  ASSERT_EQ(grid.num_faces(), kept.faces.size());
  const std::vector<uint8_t> focus = RandomFocus(kept.faces.size(), 0.1, 7);
  ExpectSuperset(kept, grid, focus, tolerance);
  const FaceGrid anew(kept, tolerance);
  const PairCandidates a = grid.Candidates(kept, focus), b = anew.Candidates(kept, focus);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.vertices, b.vertices);
}

}  // namespace
}  // namespace ms
