#include "mesh/float_robustness.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "base/error.h"
#include "mesh/mesh_checker.h"
#include "testing/test_meshes.h"

namespace ms {
namespace {

using namespace test_meshes;  // NOLINT: small shapes only

using float_robustness_internal::SegmentCrossesTriangle;
using float_robustness_internal::TriangleClosestPoints;
using float_robustness_internal::TriangleDistance;
using float_robustness_internal::TrianglesIntersectLikeOpen3d;
using float_robustness_internal::TrianglesSurelyApart;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using Triangle = float_robustness_internal::Triangle;
using V = Eigen::Vector3d;

MeshReport Check(const Mesh& m, double tolerance = 1e-6, bool allow = false) {
  MeshCheckOptions options;
  options.float_tolerance = tolerance;
  options.allow_float_issues = allow;
  return CheckMesh(m, options);
}

TEST(FloatRobustness, CleanClosedMeshesPass) {
  for (const auto& [name, mesh, edge, angle] :
       std::vector<std::tuple<std::string, Mesh, double, double>>{
           {"icosahedron", Icosahedron(), 2.0, 60.0}, {"cube", Cube(), 1.0, 45.0}}) {
    SCOPED_TRACE(name);
    const MeshReport r = Check(mesh);
    EXPECT_TRUE(r.is_valid) << r.ToTable();
    EXPECT_TRUE(r.is_float_robust);
    const FloatRobustnessReport& f = r.float_robustness;
    EXPECT_TRUE(f.face_pairs_checked);
    EXPECT_EQ(f.num_near_vertex_pairs, 0);
    EXPECT_EQ(f.num_close_face_pairs, 0);
    EXPECT_EQ(f.num_float_intersections, 0);
    ASSERT_TRUE(f.shortest_edge.has_value());
    EXPECT_NEAR(*f.shortest_edge, edge, 1e-12);
    ASSERT_TRUE(f.smallest_angle_degrees.has_value());
    EXPECT_NEAR(*f.smallest_angle_degrees, angle, 1e-9);
    EXPECT_NEAR(f.tolerance, 1e-6 * f.diagonal, 1e-18);
    EXPECT_DOUBLE_EQ(f.relative_tolerance, 1e-6);
  }
  EXPECT_NEAR(Check(Cube()).float_robustness.diagonal, std::sqrt(3.0), 1e-12);
}

TEST(FloatRobustness, NearCoincidentVerticesFail) {
  // Diagonal ~3.46; the apexes are 1e-9 of it apart, on the far side of the first corner.
  const double d = 1e-9 * 2 * std::sqrt(3.0);
  const Mesh m = ApexToApex(V(-d, -d, -d) / std::sqrt(3.0));
  const MeshReport r = Check(m);
  EXPECT_TRUE(r.is_closed_manifold) << r.ToTable();  // exact: two separate tetrahedra
  EXPECT_EQ(r.num_self_intersections, 0);
  EXPECT_FALSE(r.is_float_robust);
  EXPECT_FALSE(r.is_valid);
  const FloatRobustnessReport& f = r.float_robustness;
  EXPECT_EQ(f.num_near_vertex_pairs, 1);
  EXPECT_THAT(f.near_vertex_examples, ElementsAre(std::array<int32_t, 2>{0, 4}));
  ASSERT_TRUE(f.closest_vertex_distance.has_value());
  EXPECT_NEAR(*f.closest_vertex_distance, d, 1e-20);
  // The three faces at each apex are within the tolerance of the three at the other; they do
  // not cross (back to back), for Möller's test either.
  EXPECT_EQ(f.num_close_face_pairs, 9);
  EXPECT_EQ(f.num_float_intersections, 0);
  EXPECT_THAT(r.Problems(),
              ElementsAre(HasSubstr("near-coincident"), HasSubstr("sharing no vertex at most")));
  EXPECT_THAT(r.ToTable(), HasSubstr("NOT VALID"));
  // Relaxed: reported, but valid.
  const MeshReport allowed = Check(m, 1e-6, /*allow=*/true);
  EXPECT_TRUE(allowed.is_valid);
  EXPECT_FALSE(allowed.is_float_robust);
  EXPECT_TRUE(allowed.Problems().empty());
  EXPECT_THAT(allowed.ToTable(), HasSubstr("floating-point issues allowed"));
  // A tolerance below the gap: nothing is near.
  EXPECT_TRUE(Check(m, 1e-10).is_valid);
}

TEST(FloatRobustness, ApexOnTheOtherPlaneCrossesInDoublePrecision) {
  // The second apex a hair below the first corner's bottom face (z = 0), over its inside:
  // exactly apart, but Möller's test (its 1e-6 snap) takes it as touching, as Open3D 0.16 does
  // (the same 4 face pairs).
  const double e = 3.5e-9;  // 1e-9 of the diagonal
  const Mesh m = ApexToApex(V(e, e, -e));
  const MeshReport r = Check(m);
  EXPECT_TRUE(r.is_closed_manifold) << r.ToTable();
  EXPECT_EQ(r.num_self_intersections, 0);
  EXPECT_EQ(r.float_robustness.num_float_intersections, 4);
  EXPECT_GT(r.float_robustness.num_close_face_pairs, 0);
  EXPECT_FALSE(r.is_valid);
  EXPECT_THAT(r.Problems(), testing::Contains(HasSubstr("intersect in double precision")));
  // A zero tolerance leaves the crossings; only the option accepts them.
  const MeshReport zero = Check(m, 0);
  EXPECT_EQ(zero.float_robustness.num_near_vertex_pairs, 0);
  EXPECT_EQ(zero.float_robustness.num_float_intersections, 4);
  EXPECT_FALSE(zero.is_valid);
  EXPECT_TRUE(Check(m, 0, /*allow=*/true).is_valid);
}

TEST(FloatRobustness, NonAdjacentFacesTouchingOrCrossingFail) {
  // Nearly touching: a corner whose apex is 1e-8 (~4e-9 of the diagonal) above the middle of
  // the first corner's slanted face x + y + z = 1, pointing away from it.
  const V n = V(1, 1, 1).normalized();
  const Mesh near = Append(Corner(V(0, 0, 0), 1), Corner(V(1, 1, 1) / 3 + 1e-8 * n, 1));
  MeshReport r = Check(near);
  EXPECT_TRUE(r.is_closed_manifold) << r.ToTable();
  EXPECT_EQ(r.float_robustness.num_near_vertex_pairs, 0);
  EXPECT_EQ(r.float_robustness.num_close_face_pairs, 3);  // the slanted face, three at the apex
  ASSERT_TRUE(r.float_robustness.closest_face_pair_distance.has_value());
  EXPECT_NEAR(*r.float_robustness.closest_face_pair_distance, 1e-8, 1e-15);
  EXPECT_EQ(r.float_robustness.num_float_intersections, 3);  // Open3D: the same 3
  EXPECT_FALSE(r.is_valid);
  const MeshReport small = Check(near, 1e-10);  // the gap is above this tolerance
  EXPECT_EQ(small.float_robustness.num_close_face_pairs, 0);
  EXPECT_EQ(small.float_robustness.num_float_intersections, 3);

  // A real crossing: the exact test and both floating-point tests see it.
  const Mesh crossing = Append(Corner(V(0, 0, 0), 1), Corner(V(1, 1, 1) / 3 - 0.1 * n, 1));
  r = Check(crossing);
  EXPECT_EQ(r.num_self_intersections, 3);
  EXPECT_EQ(r.float_robustness.num_float_intersections, 3);
  EXPECT_EQ(r.float_robustness.num_close_face_pairs, 3);
  EXPECT_EQ(*r.float_robustness.closest_face_pair_distance, 0.0);
  EXPECT_FALSE(r.is_valid);
}

// The pair searches run slab by slab along x; slabs of a few boxes must find what one search
// over all the boxes finds: the same pairs of near vertices, close faces and crossing faces, with
// and without focus faces.
TEST(FloatRobustness, SlabsFindWhatOneSearchFinds) {
  Mesh soup;  // small triangles scattered in a box, many crossing or near one another
  uint64_t state = 12345;
  const auto next = [&state] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / static_cast<double>(1ULL << 53);
  };
  for (int t = 0; t < 400; ++t) {
    const V corner(next() * 4, next(), next());
    const auto base = static_cast<int32_t>(soup.vertices.size());
    soup.vertices.push_back(corner);
    soup.vertices.push_back(corner + V(next(), next(), next()) * 0.3);
    soup.vertices.push_back(corner + V(next(), next(), next()) * 0.3);
    soup.faces.push_back({base, base + 1, base + 2});
  }
  soup.vertices.push_back(soup.vertices[7] + V(1e-9, 0, 0));  // a near pair, the lone vertex
  soup.faces.push_back({static_cast<int32_t>(soup.vertices.size()) - 1, 0, 4});
  const std::vector<uint8_t> usable(soup.faces.size(), 1);
  std::vector<uint8_t> some(soup.faces.size(), 0);
  for (size_t f = 0; f < some.size(); f += 3) some[f] = 1;
  some.back() = 1;  // the near pair's
  for (const std::vector<uint8_t>& focus : {std::vector<uint8_t>{}, some}) {
    SCOPED_TRACE(focus.empty() ? "whole" : "focus");
    FloatRobustnessOptions one;
    one.relative_tolerance = 1e-3;
    one.max_examples = 1 << 20;
    one.max_pairs = 1 << 20;
    one.focus_faces = focus;
    one.boxes_per_slab = 1 << 20;
    FloatRobustnessOptions slabs = one;
    slabs.boxes_per_slab = 7;
    const FloatRobustnessReport a = CheckFloatRobustness(soup, usable, one);
    const FloatRobustnessReport b = CheckFloatRobustness(soup, usable, slabs);
    EXPECT_GT(a.num_float_intersections, focus.empty() ? 100 : 30);
    EXPECT_GT(a.num_close_face_pairs, a.num_float_intersections);
    EXPECT_GE(a.num_near_vertex_pairs, 1);
    EXPECT_EQ(a.near_vertex_examples, b.near_vertex_examples);
    EXPECT_EQ(a.close_face_pair_examples, b.close_face_pair_examples);
    EXPECT_EQ(a.float_intersection_examples, b.float_intersection_examples);
    EXPECT_EQ(a.num_close_face_pairs, b.num_close_face_pairs);
  }
}

TEST(FloatRobustness, NeedleFacesReportTheShortestEdgeAndSmallestAngle) {
  const double needle = 1e-4;
  const Mesh m = Bipyramid(needle);
  const MeshReport r = Check(m);
  EXPECT_TRUE(r.is_valid) << r.ToTable();  // short, but far above the tolerance
  const FloatRobustnessReport& f = r.float_robustness;
  ASSERT_TRUE(f.shortest_edge.has_value());
  EXPECT_NEAR(*f.shortest_edge, needle, 1e-15);
  EXPECT_THAT(f.shortest_edge_vertices, ElementsAre(1, 2));
  // The smallest angle is at an apex, opposite the needle edge.
  const V a = m.vertices[1] - m.vertices[3], b = m.vertices[2] - m.vertices[3];
  const double expected = std::asin(a.cross(b).norm() / (a.norm() * b.norm())) * 180 / M_PI;
  ASSERT_TRUE(f.smallest_angle_degrees.has_value());
  EXPECT_NEAR(*f.smallest_angle_degrees, expected, 1e-9 * expected);
  EXPECT_LT(*f.smallest_angle_degrees, 0.01);
  EXPECT_THAT(f.smallest_angle_vertex, testing::AnyOf(3, 4));
  EXPECT_THAT(f.smallest_angle_face, testing::AnyOf(1, 4));
  EXPECT_THAT(r.ToTable(), HasSubstr("edge 1-2 of face"));

  // Shorter than the tolerance: the needle's ends are near-coincident vertices.
  const MeshReport tiny = Check(Bipyramid(1e-9));
  EXPECT_TRUE(tiny.is_closed_manifold);
  EXPECT_FALSE(tiny.is_valid);
  EXPECT_THAT(tiny.float_robustness.near_vertex_examples,
              ElementsAre(std::array<int32_t, 2>{1, 2}));
  EXPECT_TRUE(Check(Bipyramid(1e-9), 1e-6, /*allow=*/true).is_valid);
}

TEST(FloatRobustness, ToleranceZeroAndAbsoluteTolerance) {
  // Two distinct vertices at the same position: found even with a zero tolerance.
  Mesh m = Append(Cube(), Cube());
  for (size_t v = 8; v < 16; ++v) m.vertices[v] += V(1, 1, 1);  // corner (1,1,1) twice
  MeshReport r = Check(m, 0);
  EXPECT_EQ(r.float_robustness.tolerance, 0.0);
  EXPECT_EQ(r.float_robustness.num_near_vertex_pairs, 1);
  EXPECT_THAT(r.float_robustness.near_vertex_examples, ElementsAre(std::array<int32_t, 2>{7, 8}));
  EXPECT_EQ(*r.float_robustness.closest_vertex_distance, 0.0);

  // An absolute tolerance replaces the relative one.
  MeshCheckOptions options;
  options.float_tolerance_abs = 0.25;
  r = CheckMesh(Icosahedron(), options);
  EXPECT_EQ(r.float_robustness.tolerance, 0.25);
  EXPECT_TRUE(r.is_float_robust);
  options.float_tolerance_abs = 2.5;  // more than an edge: every neighbour is "near"
  r = CheckMesh(Icosahedron(), options);
  EXPECT_EQ(r.float_robustness.num_near_vertex_pairs, 30);  // the 30 edges
  EXPECT_FALSE(r.is_valid);
}

TEST(FloatRobustness, FacePairsAreSkippedWithTheSelfIntersectionTest) {
  const double e = 3.5e-9;
  const Mesh m = ApexToApex(V(e, e, -e));
  MeshCheckOptions options;
  options.check_self_intersections = false;
  const MeshReport r = CheckMesh(m, options);
  EXPECT_FALSE(r.float_robustness.face_pairs_checked);
  EXPECT_EQ(r.float_robustness.num_float_intersections, 0);
  EXPECT_EQ(r.float_robustness.num_near_vertex_pairs, 1);  // still checked: it is cheap
  EXPECT_FALSE(r.is_valid);
  EXPECT_THAT(r.ToTable(), HasSubstr("not checked"));
  const nlohmann::json j = nlohmann::json::parse(r.ToJson());
  EXPECT_TRUE(j["float_robustness"]["close_face_pairs"].is_null());
  EXPECT_TRUE(j["float_robustness"]["float_intersections"].is_null());
}

TEST(FloatRobustness, JsonAndLimits) {
  const double e = 3.5e-9;
  const Mesh m = ApexToApex(V(e, e, -e));
  const nlohmann::json j = nlohmann::json::parse(Check(m).ToJson("m.ply"));
  EXPECT_EQ(j["valid"], false);
  EXPECT_EQ(j["closed_manifold"], true);
  EXPECT_EQ(j["float_robust"], false);
  const auto& f = j["float_robustness"];
  EXPECT_EQ(f["near_vertex_pairs"], 1);
  EXPECT_GT(f["float_intersections"].get<int>(), 0);
  EXPECT_EQ(f["examples"]["near_vertex_pairs"].size(), 1u);
  EXPECT_DOUBLE_EQ(f["relative_tolerance"].get<double>(), 1e-6);
  EXPECT_TRUE(f["shortest_edge"].is_number());
  EXPECT_TRUE(f["smallest_angle_degrees"].is_number());

  MeshCheckOptions options;
  options.max_self_intersections = 1;
  const MeshReport limited = CheckMesh(m, options);
  EXPECT_EQ(limited.float_robustness.num_close_face_pairs, 1);
  EXPECT_TRUE(limited.float_robustness.close_face_pairs_truncated);
  EXPECT_THAT(limited.Problems(), testing::Contains(HasSubstr("at least 1 pairs of faces")));

  // A mesh with no usable face has no edge or angle.
  const nlohmann::json empty = nlohmann::json::parse(Check(Mesh{}).ToJson());
  EXPECT_TRUE(empty["float_robustness"]["shortest_edge"].is_null());
}

TEST(FloatRobustness, OptionsAreChecked) {
  MeshCheckOptions options;
  options.float_tolerance = -1;
  try {
    CheckMesh(Cube(), options);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--float-tolerance must be >= 0, got -1");
  }
  options.float_tolerance = NAN;
  EXPECT_THROW(options.Check(), InputError);
  options.float_tolerance = 1e-6;
  options.float_tolerance_abs = -0.5;
  EXPECT_THROW(
      {
        try {
          options.Check();
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), HasSubstr("--float-tolerance-abs must be >= 0, got -0.5"));
          throw;
        }
      },
      InputError);
}

// A cells x cells grid over [0, 1]^2 at height z, two faces a cell.
Mesh Grid(int cells, double z) {
  Mesh m;
  for (int j = 0; j <= cells; ++j) {
    for (int i = 0; i <= cells; ++i) m.vertices.push_back(V(i, j, 0) / cells + V(0, 0, z));
  }
  const auto at = [&](int i, int j) { return j * (cells + 1) + i; };
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      m.faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return m;
}

// While the vertices move along the segments from one place to another, a check that takes its
// pairs from FindPairCandidates finds what a check that searches finds: two sheets 0.01 apart,
// their vertices moved at random by up to 0.02 (some pairs come close or cross), checked at
// fractions of the move as the halving rounds of refine/mesh_moves.h do, with and without focus.
TEST(FloatRobustness, PairCandidatesFindWhatASearchFinds) {
  const Mesh start = Append(Grid(12, 0), Grid(12, 0.01));
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<V> to = start.vertices;
  for (size_t v = 0; v < to.size(); v += 2) {
    const double x = unit(random), y = unit(random), z = unit(random);
    to[v] += V(0.01 * x, 0.01 * y, 0.02 * z);
  }
  const double tolerance = 0.003;
  for (bool focused : {false, true}) {
    std::vector<uint8_t> focus;
    if (focused) {
      focus.assign(start.faces.size(), 0);
      for (size_t f = 0; f < start.faces.size(); f += 3) focus[f] = 1;
    }
    const PairCandidates candidates = FindPairCandidates(start, to, tolerance, focus);
    for (double s : {1.0, 0.5, 0.25, 0.125, 0.0}) {
      Mesh m = start;
      for (size_t v = 0; v < m.vertices.size(); ++v) {
        m.vertices[v] = start.vertices[v] + s * (to[v] - start.vertices[v]);
      }
      FloatRobustnessOptions options;
      options.absolute_tolerance = tolerance;
      options.max_examples = 1 << 20;
      options.focus_faces = focus;
      std::set<std::array<int64_t, 2>> searched_pairs, listed_pairs;
      options.on_box_pair = [&](int64_t f, int64_t g) { searched_pairs.insert({f, g}); };
      const std::vector<uint8_t> usable(m.faces.size(), 1);
      const FloatRobustnessReport searched = CheckFloatRobustness(m, usable, options);
      options.candidates = &candidates;
      options.on_box_pair = [&](int64_t f, int64_t g) { listed_pairs.insert({f, g}); };
      const FloatRobustnessReport listed = CheckFloatRobustness(m, usable, options);
      SCOPED_TRACE(testing::Message() << "focus " << focused << ", s = " << s);
      EXPECT_EQ(listed.near_vertex_examples, searched.near_vertex_examples);
      EXPECT_EQ(listed.close_face_pair_examples, searched.close_face_pair_examples);
      EXPECT_EQ(listed.float_intersection_examples, searched.float_intersection_examples);
      EXPECT_EQ(listed_pairs, searched_pairs);
      if (s == 1.0) {
        EXPECT_GT(searched.num_close_face_pairs, 0);
      }
    }
  }
}

// ----- The kernels. ----------------------------------------------------------------------------

TEST(FloatRobustnessKernels, TriangleTriangleLikeOpen3d) {
  const Triangle t = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  auto shifted = [](Triangle x, const V& d) {
    for (auto& p : x) p += d;
    return x;
  };
  auto rotated = [](Triangle x) {
    for (auto& p : x) p = Rotation() * p;
    return x;
  };
  // Piercing, apart, touching at a vertex, coplanar overlapping, coplanar apart.
  EXPECT_TRUE(TrianglesIntersectLikeOpen3d(t, {V(0.2, 0.2, -1), V(0.3, 0.2, 1), V(0.2, 0.3, 1)}));
  EXPECT_FALSE(TrianglesIntersectLikeOpen3d(t, shifted(t, V(0, 0, 1))));
  EXPECT_TRUE(TrianglesIntersectLikeOpen3d(t, {V(0.2, 0.2, 0), V(0.2, 0.2, 1), V(1, 1, 1)}));
  EXPECT_TRUE(TrianglesIntersectLikeOpen3d(t, shifted(t, V(0.2, 0.2, 0))));
  EXPECT_FALSE(TrianglesIntersectLikeOpen3d(t, shifted(t, V(2, 2, 0))));
  // The 1e-6 snap: a parallel triangle 1e-9 above counts as in the plane, hence overlapping,
  // unless the gap is along a coordinate axis, where the per-axis scaling blows it up. These
  // are Open3D 0.16's answers (TriangleMesh.is_intersecting on one-triangle meshes).
  EXPECT_TRUE(TrianglesIntersectLikeOpen3d(rotated(t), rotated(shifted(t, V(0.2, 0.2, 1e-9)))));
  EXPECT_FALSE(TrianglesIntersectLikeOpen3d(t, shifted(t, V(0.2, 0.2, 1e-9))));
  EXPECT_FALSE(TrianglesIntersectLikeOpen3d(rotated(t), rotated(shifted(t, V(0.2, 0.2, 1e-7)))));
}

TEST(FloatRobustnessKernels, SegmentCrossesTriangle) {
  const Triangle t = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  EXPECT_TRUE(SegmentCrossesTriangle(V(0.2, 0.2, -1), V(0.2, 0.2, 1), t));
  EXPECT_TRUE(SegmentCrossesTriangle(V(0.2, 0.2, 0), V(0.2, 0.2, 1), t));  // touching
  EXPECT_FALSE(SegmentCrossesTriangle(V(0.8, 0.8, -1), V(0.8, 0.8, 1), t));
  EXPECT_FALSE(SegmentCrossesTriangle(V(0.2, 0.2, 0.5), V(0.2, 0.2, 1), t));
  EXPECT_FALSE(SegmentCrossesTriangle(V(-1, 0.2, 0), V(2, 0.2, 0), t));  // in the plane
}

TEST(FloatRobustnessKernels, TriangleDistance) {
  const Triangle t = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  // Parallel, 0.5 above: a vertex over the inside.
  EXPECT_NEAR(TriangleDistance(t, {V(0.2, 0.2, 0.5), V(0.3, 0.2, 0.5), V(0.2, 0.3, 0.5)}), 0.5,
              1e-15);
  // Edge to edge: the segment x = 2, z = 1 (along y) and the edge (1,0,0)-(0,1,0) ... the
  // closest points are (1,0,0) and (2,0,1): sqrt(2).
  EXPECT_NEAR(TriangleDistance(t, {V(2, -1, 1), V(2, 1, 1), V(3, 0, 5)}), std::sqrt(2.0), 1e-15);
  // Skew edges crossing over each other: the distance between the lines.
  EXPECT_NEAR(TriangleDistance(t, {V(0.25, 0.25, 0.1), V(0.25, 0.25, 5), V(0.5, 0.5, 5)}), 0.1,
              1e-15);
  EXPECT_EQ(TriangleDistance(t, {V(0.2, 0.2, -1), V(0.3, 0.2, 1), V(0.2, 0.3, 1)}), 0.0);
  // Coplanar up to rounding and 0.083 apart: an edge that seems to cross the other triangle
  // (the orientations are rounding noise there) but does not meet it is measured.
  const Triangle p = {V(0.86246482234279265, 0.39513222262418379, -0.45767676201338936),
                      V(0.62829662265936914, -0.33111240537558384, -0.24659929040345996),
                      V(-0.28941908192973931, -0.58955085508104843, -0.27440284102342993)};
  const Triangle q = {V(0.31023998964440208, 0.32677762434707047, -0.50320529793519475),
                      V(0.54080833303053377, 1.4062755398011144, -0.83144632927011708),
                      V(1.6137559259402794, 0.67975285061385571, -0.45905167675938108)};
  EXPECT_NEAR(TriangleDistance(p, q), 0.0830449, 1e-6);
  EXPECT_FALSE(TrianglesIntersectLikeOpen3d(p, q));
  // A degenerate (zero-area) triangle is measured through its edges.
  EXPECT_NEAR(TriangleDistance(t, {V(2, 0, 0), V(3, 0, 0), V(4, 0, 0)}), 1.0, 1e-15);
}

// The cheap pre-test never spares a pair the distance would flag: over random pairs of triangles
// (coplanar ones and near misses included), "surely apart by d" means farther than d; and it
// does spare pairs a face apart in a flat mesh.
TEST(FloatRobustnessKernels, SurelyApartNeverHidesAClosePair) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  const auto point = [&](double spread) -> V {
    const double x = unit(random), y = unit(random), z = unit(random);
    return spread * V(x, y, z);
  };
  int apart = 0;
  for (int i = 0; i < 20000; ++i) {
    Triangle p = {point(1), point(1), point(1)}, q;
    const V shift = point(1.5);
    for (int k = 0; k < 3; ++k) q[k] = shift + point(1);
    if (i % 3 == 0) {  // in p's plane
      const V n = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
      for (V& x : q) x -= n * n.dot(x - p[0]);
    }
    const double d = i % 2 == 0 ? 0 : 0.05;
    if (!TrianglesSurelyApart(p, q, d)) continue;
    ++apart;
    ASSERT_GT(TriangleDistance(p, q), d) << i;
  }
  EXPECT_GT(apart, 2000);
  // Two faces of a flat grid with one face between them: apart, though their boxes meet.
  const Triangle a = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  const Triangle b = {V(1, 1, 0), V(2, 1, 0), V(1, 2, 0)};
  EXPECT_TRUE(TrianglesSurelyApart(a, b, 0.1));
  EXPECT_FALSE(TrianglesSurelyApart(a, b, 1));
  EXPECT_FALSE(TrianglesSurelyApart(a, {V(0.2, 0.2, -1), V(0.3, 0.2, 1), V(0.2, 0.3, 1)}, 0));
}

TEST(FloatRobustnessKernels, TriangleClosestPoints) {
  const Triangle t = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  const auto expect = [&](const Triangle& q, const V& on_t, const V& on_q) {
    const auto c = TriangleClosestPoints(t, q);
    EXPECT_NEAR((c[0] - on_t).norm(), 0, 1e-12) << c[0].transpose();
    EXPECT_NEAR((c[1] - on_q).norm(), 0, 1e-12) << c[1].transpose();
    EXPECT_NEAR((c[0] - c[1]).norm(), TriangleDistance(t, q), 1e-12);
  };
  // A vertex of q above t's interior.
  expect({V(0.2, 0.2, 0.5), V(0.3, 0.2, 2), V(0.2, 0.3, 2)}, V(0.2, 0.2, 0), V(0.2, 0.2, 0.5));
  // A vertex of t below q's interior.
  expect({V(-1, -1, -0.25), V(3, -1, -0.25), V(-1, 3, -0.25)}, V(0, 0, 0), V(0, 0, -0.25));
  // Skew edges: t's hypotenuse and an edge of q rising over it (q in the plane x = y).
  expect({V(1, 1, -0.8), V(0, 0, 1.2), V(2, 2, 5)}, V(0.5, 0.5, 0),
         V(17.0 / 30, 17.0 / 30, 2.0 / 30));
}

}  // namespace
}  // namespace ms
