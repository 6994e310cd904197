#include "mesh/float_cleanup.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>

#include "mesh/mesh_checker.h"
#include "testing/test_meshes.h"

namespace ms {
namespace {

using namespace test_meshes;  // NOLINT: small shapes only

// check-mesh's verdict with every test on: exact (closed 2-manifold, no self-intersection)
// and in floating point.
void ExpectValidAndRobust(const Mesh& mesh) {
  const MeshReport r = CheckMesh(mesh, MeshCheckOptions{});
  EXPECT_TRUE(r.is_valid) << r.ToTable();
  EXPECT_TRUE(r.is_float_robust) << r.ToTable();
}

// The cleanup, each round's re-check compared with a whole-mesh check.
FloatCleanupStats Clean(Mesh* mesh, std::vector<uint8_t>* scaffold = nullptr) {
  FloatCleanupOptions options;
  options.verify_rechecks = true;
  return CleanForFloatingPoint(mesh, scaffold, options);
}

bool HasVertex(const Mesh& mesh, const V& p) {
  return std::find(mesh.vertices.begin(), mesh.vertices.end(), p) != mesh.vertices.end();
}

// Face f split in three around a point `offset` away from its first corner: the new vertex
// and that corner are near-coincident, and the faces around them needles.
Mesh SplitNearCorner(Mesh mesh, size_t f, double offset) {
  const auto t = mesh.faces[f];
  const V centre = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3;
  const V corner = mesh.vertices[t[0]];
  const auto p = static_cast<int32_t>(mesh.vertices.size());
  mesh.vertices.push_back(corner + offset * (centre - corner).normalized());
  mesh.faces[f] = {t[0], t[1], p};
  mesh.faces.push_back({t[1], t[2], p});
  mesh.faces.push_back({t[2], t[0], p});
  return mesh;
}

TEST(FloatCleanup, CleanMeshesAreLeftAlone) {
  for (const Mesh& original : {Icosahedron(), Cube()}) {
    Mesh mesh = original;
    const FloatCleanupStats stats = Clean(&mesh);
    EXPECT_EQ(stats.problems_before, 0);
    EXPECT_EQ(stats.collapses + stats.splits, 0);
    EXPECT_EQ(mesh.vertices, original.vertices);
    EXPECT_EQ(mesh.faces, original.faces);
  }
}

TEST(FloatCleanup, NearCoincidentVertexIsCollapsedOntoItsTwin) {
  const Mesh original = Icosahedron();
  Mesh mesh = SplitNearCorner(original, 3, 1e-9);
  ASSERT_FALSE(CheckMesh(mesh, MeshCheckOptions{}).is_float_robust);
  std::vector<uint8_t> scaffold(mesh.vertices.size(), 0);
  const FloatCleanupStats stats = Clean(&mesh, &scaffold);
  EXPECT_GT(stats.problems_before, 0);
  EXPECT_EQ(stats.problems_after, 0);
  EXPECT_EQ(stats.collapses, 1);
  EXPECT_EQ(stats.splits, 0);
  ExpectValidAndRobust(mesh);
  // Back to the icosahedron: one of the twins is gone, every position is an original one.
  EXPECT_EQ(mesh.vertices.size(), original.vertices.size());
  EXPECT_EQ(mesh.faces.size(), original.faces.size());
  EXPECT_EQ(scaffold.size(), mesh.vertices.size());
  for (const V& p : mesh.vertices) {
    EXPECT_TRUE(HasVertex(original, p) ||
                (p - original.vertices[original.faces[3][0]]).norm() < 1e-8);
  }
}

TEST(FloatCleanup, CollapseKeepsTheSurfaceVertexOverTheScaffold) {
  Mesh mesh = SplitNearCorner(Icosahedron(), 3, 1e-9);
  const V corner = mesh.vertices[Icosahedron().faces[3][0]];
  const V twin = mesh.vertices.back();
  // The corner is scaffolding (a Steiner point), its twin a real point: the twin stays.
  std::vector<uint8_t> scaffold(mesh.vertices.size(), 0);
  scaffold[Icosahedron().faces[3][0]] = 1;
  Clean(&mesh, &scaffold);
  EXPECT_TRUE(HasVertex(mesh, twin));
  EXPECT_FALSE(HasVertex(mesh, corner));
  EXPECT_EQ(std::count(scaffold.begin(), scaffold.end(), 1), 0);
}

// Edge (a, b) split 1e-9 from a: two needles around a near-coincident pair.
Mesh SplitEdgeNearEnd(Mesh mesh, int32_t a, int32_t b, double offset) {
  const auto m = static_cast<int32_t>(mesh.vertices.size());
  mesh.vertices.push_back(mesh.vertices[a] + offset * (mesh.vertices[b] - mesh.vertices[a]));
  std::vector<std::array<int32_t, 3>> faces;
  for (const auto& t : mesh.faces) {
    bool split = false;
    for (int i = 0; i < 3 && !split; ++i) {
      const int32_t x = t[i], y = t[(i + 1) % 3], z = t[(i + 2) % 3];
      if ((x == a && y == b) || (x == b && y == a)) {
        faces.push_back({x, m, z});
        faces.push_back({m, y, z});
        split = true;
      }
    }
    if (!split) faces.push_back(t);
  }
  mesh.faces = faces;
  return mesh;
}

TEST(FloatCleanup, NeedlesAreCollapsed) {
  const Mesh original = Icosahedron();
  Mesh mesh = SplitEdgeNearEnd(original, original.faces[0][0], original.faces[0][1], 1e-9);
  for (V& p : mesh.vertices) p = Rotation() * p;
  ASSERT_FALSE(CheckMesh(mesh, MeshCheckOptions{}).is_float_robust);
  const FloatCleanupStats stats = Clean(&mesh);
  EXPECT_EQ(stats.problems_after, 0);
  EXPECT_EQ(stats.collapses, 1);
  ExpectValidAndRobust(mesh);
  EXPECT_EQ(mesh.faces.size(), original.faces.size());
}

// A bipyramid with a needle cannot lose an edge and stay a 2-manifold (the link condition
// fails everywhere): the mesh is left as it was, and the problems are reported.
TEST(FloatCleanup, WhatCannotBeCleanedIsLeftValidAndReported) {
  Mesh mesh = Bipyramid(1e-8);
  for (V& p : mesh.vertices) p = Rotation() * p;
  const Mesh original = mesh;
  const FloatCleanupStats stats = Clean(&mesh);
  EXPECT_GT(stats.problems_before, 0);
  EXPECT_EQ(stats.problems_after, stats.problems_before);
  EXPECT_EQ(stats.collapses + stats.splits, 0);
  EXPECT_EQ(mesh.vertices, original.vertices);
  EXPECT_EQ(mesh.faces, original.faces);
  // The same restored by the caller (the cleanup then keeps no copy of its own).
  Mesh again = original;
  const FloatCleanupStats from_copy =
      CleanForFloatingPoint(&again, nullptr, {}, [&original] { return original; });
  EXPECT_EQ(from_copy.problems_after, stats.problems_before);
  EXPECT_EQ(again.vertices, original.vertices);
  EXPECT_EQ(again.faces, original.faces);
}

// A tiny tetrahedron (vertices 4-7) 1e-3 above the middle of a face 100 long and 0.01 wide
// (vertices 0-3): farther apart than the tolerance (2e-4 here), yet Open3D's test calls them
// intersecting: its plane distances, scaled by the pair's extent, snap to 0 under 1e-6.
Mesh TinyCornerOverASkinnyFace() {
  Mesh skinny;
  skinny.vertices = {{0, 0, 0}, {100, 0, 0}, {50, 0.01, 0}, {50, 0.005, -10}};
  skinny.faces = {{0, 1, 2}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  const V centre =
      (skinny.vertices[0] + skinny.vertices[1] + skinny.vertices[2] + skinny.vertices[3]) / 4;
  for (size_t f = 0; f < 4; ++f) OrientAwayFrom(&skinny, f, centre);
  Mesh mesh = Append(skinny, Corner(V(50, 0.004, 1e-3), 1e-3));
  for (V& p : mesh.vertices) p = Rotation() * p;
  return mesh;
}

// Splitting the large face's edges fixes it without moving the surface.
TEST(FloatCleanup, SkinnyFaceOverATinyOneIsSplitAway) {
  Mesh mesh = TinyCornerOverASkinnyFace();
  const MeshReport before = CheckMesh(mesh, MeshCheckOptions{});
  ASSERT_GT(before.float_robustness.num_float_intersections, 0) << before.ToTable();
  ASSERT_EQ(before.float_robustness.num_close_face_pairs, 0);
  const Mesh original = mesh;
  const FloatCleanupStats stats = Clean(&mesh);
  EXPECT_EQ(stats.problems_after, 0);
  EXPECT_EQ(stats.collapses, 0);
  EXPECT_GT(stats.splits, 0);
  ExpectValidAndRobust(mesh);
  // Nothing moved: every original vertex is there, and the area is the same.
  for (const V& p : original.vertices) EXPECT_TRUE(HasVertex(mesh, p));
  EXPECT_NEAR(mesh.SurfaceArea(), original.SurfaceArea(), 1e-9 * original.SurfaceArea());
}

TEST(FloatCleanup, SplitVertexOfAScaffoldEdgeIsScaffold) {
  Mesh mesh = TinyCornerOverASkinnyFace();
  std::vector<uint8_t> scaffold(mesh.vertices.size(), 0);
  for (int v = 0; v < 4; ++v) scaffold[v] = 1;  // the skinny tetrahedron is all scaffolding
  const FloatCleanupStats stats = Clean(&mesh, &scaffold);
  ASSERT_GT(stats.splits, 0);
  ASSERT_EQ(scaffold.size(), mesh.vertices.size());
  EXPECT_EQ(std::count(scaffold.begin(), scaffold.end(), 0), 4);  // the tiny corner only
}

// Two unit cubes face to face, 1e-7 of the diagonal apart: both sheets of a thin wall, and the
// cubes' side faces edge to edge across the gap, all with edges (1) far too long to collapse
// (the bound is 1e-3 of the diagonal). The cleanup moves corners apart, 2 tolerances a move;
// no vertex is made or removed, and none moves far.
TEST(FloatCleanup, ThinWallIsMovedApartWhereNoEdgeCanCollapse) {
  Mesh second = Cube();
  for (V& p : second.vertices) p.x() += 1 + 1e-7 * std::sqrt(6.0);
  Mesh mesh = Append(Cube(), second);
  for (V& p : mesh.vertices) p = Rotation() * p;
  const Mesh original = mesh;
  ASSERT_FALSE(CheckMesh(mesh, MeshCheckOptions{}).is_float_robust);
  const FloatCleanupStats stats = Clean(&mesh);
  EXPECT_GT(stats.problems_before, 0);
  EXPECT_EQ(stats.problems_after, 0);
  EXPECT_EQ(stats.collapses, 0);
  EXPECT_GT(stats.moves, 0);
  ExpectValidAndRobust(mesh);
  ASSERT_EQ(mesh.vertices.size(), original.vertices.size());
  ASSERT_EQ(mesh.faces.size(), original.faces.size());
  // Each vertex is where it was or a few moves away (in more than one round, or along the
  // normals of the wall and of a side face).
  for (const V& p : mesh.vertices) {
    double nearest = INFINITY;
    for (const V& q : original.vertices) nearest = std::min(nearest, (p - q).norm());
    EXPECT_LE(nearest, 4 * 2 * stats.tolerance);
  }
}

// A fin: a flat tetrahedron whose two long faces are folded onto each other at its sharp edge.
Mesh Fin(const V& edge_start, double edge_length, double length, double half_width) {
  Mesh fin;
  const V e = edge_start;
  fin.vertices = {e, e + V(0, 0, edge_length), e + V(length, half_width, edge_length / 2),
                  e + V(length, -half_width, edge_length / 2)};
  fin.faces = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  OrientOutward(&fin);
  return fin;
}

// `mesh`, turned off the axes, is not float-robust and the cleanup makes it so by moves.
void ExpectCleanedByMoves(Mesh mesh) {
  for (V& p : mesh.vertices) p = Rotation() * p;
  ASSERT_FALSE(CheckMesh(mesh, MeshCheckOptions{}).is_float_robust);
  const FloatCleanupStats stats = Clean(&mesh);
  EXPECT_GT(stats.problems_before, 0);
  EXPECT_EQ(stats.problems_after, 0);
  EXPECT_GT(stats.moves, 0);
  ExpectValidAndRobust(mesh);
}

// A fin's sharp edge within the tolerance of a cube's face. Moving either face along the
// other's normal only slides it sideways: they are parted along the line through their closest
// points.
TEST(FloatCleanup, FinEdgeIsMovedAwayFromTheFaceItAlmostTouches) {
  ExpectCleanedByMoves(
      Append(Cube(), Fin(V(1 + 1e-7 * std::sqrt(6.0), 0.5, 0.3), 0.4, 0.5, 0.004)));
}

// The same fin against a thin plate, a flat tetrahedron folded at its edges too: every move
// near them touches a fold, which may stay as long as it gets no sharper.
TEST(FloatCleanup, FinEdgeIsMovedAwayFromThePlateItAlmostTouches) {
  Mesh plate;
  plate.vertices = {V(1, 0, 0), V(1, 1, 0), V(1, 0.5, 1), V(1 - 0.005, 0.5, 0.4)};
  plate.faces = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
  OrientOutward(&plate);
  ExpectCleanedByMoves(Append(plate, Fin(V(1 + 1e-7 * std::sqrt(6.0), 0.5, 0.3), 0.4, 0.5, 0.004)));
}

// The icosahedron with each face cut in four `levels` times, projected to the unit sphere.
Mesh Sphere(int levels) {
  Mesh mesh = Icosahedron();
  for (V& p : mesh.vertices) p.normalize();
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int32_t, int32_t>, int32_t> midpoint;
    const auto middle = [&](int32_t a, int32_t b) {
      const auto key = std::minmax(a, b);
      const auto [it, made] = midpoint.insert({key, static_cast<int32_t>(mesh.vertices.size())});
      if (made) mesh.vertices.push_back((mesh.vertices[a] + mesh.vertices[b]).normalized());
      return it->second;
    };
    std::vector<std::array<int32_t, 3>> faces;
    for (const auto& [a, b, c] : mesh.faces) {
      const int32_t ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      faces.insert(faces.end(), {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}});
    }
    mesh.faces = faces;
  }
  return mesh;
}

// `faces_per_split` 2: no two split faces share a vertex; 1: every face, so that near-vertex
// clusters leave problems on the faces a round makes.
Mesh SphereWithSplitCorners(bool clusters) {
  Mesh mesh = Sphere(3);
  std::vector<uint8_t> used(mesh.vertices.size(), 0);
  const size_t faces = mesh.faces.size();
  for (size_t f = 0; f < faces; ++f) {
    const auto t = mesh.faces[f];
    if (!clusters && (used[t[0]] || used[t[1]] || used[t[2]])) continue;
    for (int32_t v : t) used[v] = 1;
    mesh = SplitNearCorner(mesh, f, 1e-9 * static_cast<double>(1 + f % 5));
  }
  for (V& p : mesh.vertices) p = Rotation() * p;
  return mesh;
}

// After the first round the cleanup checks only the faces each round made and carries the
// other problems over; verify_rechecks compares that with a whole-mesh check after every round
// (and stops the program on a difference). Faces split near a corner give hundreds of near
// vertices and needles over several rounds; with clusters of them, the faces a round makes have
// problems of their own.
TEST(FloatCleanup, CheckingWhatARoundMadeEqualsCheckingTheWholeMesh) {
  for (const bool clusters : {false, true}) {
    Mesh mesh = SphereWithSplitCorners(clusters);
    std::vector<uint8_t> scaffold(mesh.vertices.size(), 0);
    for (size_t v = 0; v < scaffold.size(); v += 3) scaffold[v] = 1;
    FloatCleanupOptions options;
    options.verify_rechecks = true;
    const FloatCleanupStats stats = CleanForFloatingPoint(&mesh, &scaffold, options);
    EXPECT_GE(stats.rounds, 2) << clusters;
    EXPECT_GT(stats.problems_before, 100) << clusters;
    if (!clusters) {
      EXPECT_EQ(stats.problems_after, 0);
      ExpectValidAndRobust(mesh);
    }
  }
}

// The check stops its lists at max_pairs (check-mesh's report needs no more); the cleanup must
// see every problem, or each round fixes only the listed ones and the rounds can run out (a
// 4,096-camera street's final mesh had 100,105 problems and kept 7). Its own checks list at
// least one pair per face, so a cut at max_pairs does not change what it does.
TEST(FloatCleanup, ProblemsPastTheChecksListLimitAreCleanedAlike) {
  Mesh reference = SphereWithSplitCorners(false);
  std::vector<uint8_t> reference_scaffold(reference.vertices.size(), 0);
  const FloatCleanupStats expected = CleanForFloatingPoint(&reference, &reference_scaffold);
  ASSERT_GT(expected.problems_before, 100);
  Mesh mesh = SphereWithSplitCorners(false);
  std::vector<uint8_t> scaffold(mesh.vertices.size(), 0);
  FloatCleanupOptions options;
  options.check.max_pairs = 10;
  const FloatCleanupStats stats = CleanForFloatingPoint(&mesh, &scaffold, options);
  EXPECT_EQ(stats.problems_before, expected.problems_before);
  EXPECT_EQ(stats.problems_after, 0);
  EXPECT_EQ(stats.rounds, expected.rounds);
  EXPECT_EQ(mesh.vertices, reference.vertices);
  EXPECT_EQ(mesh.faces, reference.faces);
}

// 74 faces cut from the 4,096-camera street's final mesh (metres; docs/design/scalability.md)
// around two pairs that the cleanup could not separate: faces 1–3 cm across, crumpled, where every
// collapse of the pairs' own corners folds a face and every move does too. Collapsing an edge
// of a neighbour changes their surroundings until the pairs go. (An open patch: the check's
// tolerance and the collapse bound are set to the whole mesh's.)
TEST(FloatCleanup, CrumpledClusterIsCleanedThroughItsNeighbours) {
  Mesh mesh;
  mesh.vertices = {
      {160.345, -9.0, 3.30525},     {160.624, -9.0, 3.39805},     {159.601, -9.0, 2.7739},
      {159.421, -9.0, 3.64029},     {160.521, -9.0, 4.26016},     {159.013, -9.0, 3.88423},
      {159.779, -9.0, 3.88503},     {160.238, -8.81501, 4.59769}, {159.056, -9.0, 4.18159},
      {159.853, -9.0, 4.16561},     {159.845, -9.0, 3.69318},     {159.861, -9.0, 3.91566},
      {160.386, -9.0, 3.81262},     {159.536, -9.0, 4.48335},     {159.5, -9.0, 4.28115},
      {159.97, -9.0, 3.92559},      {159.93, -9.0, 3.72288},      {159.713, -9.0, 4.48855},
      {159.364, -9.0, 3.43856},     {160.68, -9.0, 3.50237},      {159.877, -9.0, 3.90839},
      {159.917, -9.0, 3.80089},     {159.373, -9.0, 3.5549},      {159.983, -9.0, 3.2132},
      {159.916, -9.0, 3.20751},     {159.799, -9.0, 4.81393},     {160.372, -9.0, 4.00275},
      {159.868, -9.0, 3.89206},     {159.965, -9.0, 2.93584},     {159.993, -9.0, 2.90746},
      {159.58, -9.36273, 3.93838},  {159.662, -8.98842, 4.56274}, {158.888, -8.91935, 4.39947},
      {159.842, -8.98781, 4.05705}, {159.574, -8.99241, 4.4883},  {159.537, -9.0, 4.44426},
      {159.928, -9.0, 3.87985},     {159.624, -9.0, 4.47665},     {158.983, -8.97124, 4.24846},
      {160.467, -9.0, 4.15342},     {160.757, -9.0, 4.17836},     {159.879, -9.0, 3.87117},
      {160.476, -9.0, 3.868},       {159.847, -8.9939, 4.11126},  {159.577, -8.99592, 4.45045},
      {159.719, -9.0, 4.34849},     {159.959, -8.99098, 3.95302}, {159.714, -9.0, 4.41217},
      {159.674, -9.0, 4.39981},
  };
  mesh.faces = {
      {0, 12, 1},   {0, 16, 12},  {0, 23, 16},  {0, 29, 23},  {1, 12, 19},  {2, 18, 24},
      {3, 5, 30},   {3, 10, 18},  {3, 14, 33},  {3, 18, 22},  {3, 22, 5},   {3, 30, 14},
      {3, 33, 7},   {4, 39, 7},   {4, 40, 39},  {5, 8, 14},   {5, 14, 30},  {5, 22, 18},
      {6, 27, 41},  {6, 46, 27},  {7, 9, 45},   {7, 17, 31},  {7, 26, 46},  {7, 31, 25},
      {7, 33, 43},  {7, 39, 26},  {7, 43, 9},   {7, 45, 47},  {7, 47, 17},  {8, 38, 14},
      {9, 43, 45},  {10, 16, 23}, {10, 23, 24}, {10, 24, 18}, {11, 20, 27}, {11, 27, 46},
      {11, 46, 20}, {12, 15, 46}, {12, 16, 15}, {12, 26, 42}, {12, 42, 19}, {12, 46, 26},
      {13, 34, 35}, {13, 35, 32}, {14, 32, 35}, {14, 34, 44}, {14, 35, 34}, {14, 44, 45},
      {14, 45, 33}, {15, 16, 21}, {17, 47, 31}, {20, 41, 27}, {21, 41, 36}, {23, 28, 24},
      {26, 39, 42}, {31, 37, 34}, {31, 47, 48}, {31, 48, 37}, {33, 45, 43}, {34, 37, 48},
      {34, 48, 44}, {39, 40, 42}, {44, 48, 45}, {45, 48, 47}, {15, 21, 36}, {15, 36, 46},
      {36, 41, 46}, {20, 46, 41}, {6, 41, 21},  {10, 21, 16}, {6, 21, 46},  {7, 46, 21},
      {3, 21, 10},  {3, 7, 21},
  };
  FloatCleanupOptions options;
  options.verify_rechecks = true;
  options.check.absolute_tolerance = 0.0076012;  // 1e-6 of the street's diagonal
  options.max_collapse_fraction = 1.0;           // the street's 1e-3 of its diagonal: 7.6 m
  const FloatCleanupStats stats = CleanForFloatingPoint(&mesh, nullptr, options);
  EXPECT_EQ(stats.problems_before, 2);
  EXPECT_EQ(stats.problems_after, 0);
  EXPECT_GE(stats.rounds, 2);  // the pairs go only after their surroundings changed
  FloatRobustnessOptions check = options.check;
  check.absolute_tolerance = stats.tolerance;
  const FloatRobustnessReport report =
      CheckFloatRobustness(mesh, std::vector<uint8_t>(mesh.faces.size(), 1), check);
  EXPECT_EQ(
      report.num_near_vertex_pairs + report.num_close_face_pairs + report.num_float_intersections,
      0);
}

TEST(FloatCleanup, OptionsAreChecked) {
  Mesh mesh = Icosahedron();
  FloatCleanupOptions bad;
  bad.check.relative_tolerance = -1;
  EXPECT_ANY_THROW(CleanForFloatingPoint(&mesh, nullptr, bad));
  std::vector<uint8_t> wrong_size(3, 0);
  EXPECT_DEATH(CleanForFloatingPoint(&mesh, &wrong_size), "one scaffold flag per vertex");
}

}  // namespace
}  // namespace ms
