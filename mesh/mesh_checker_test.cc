#include "mesh/mesh_checker.h"

// The test may use CGAL directly: it is an oracle for the self-intersection search.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "base/error.h"
#include "testing/test_meshes.h"

namespace ms {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using Face = std::array<int32_t, 3>;

using test_meshes::Append;
using test_meshes::OrientOutward;

Mesh Tetrahedron(const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
  Mesh m;
  m.vertices = {offset, offset + Eigen::Vector3d(1, 0, 0), offset + Eigen::Vector3d(0, 1, 0),
                offset + Eigen::Vector3d(0, 0, 1)};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // outward
  return m;
}

void AddQuad(Mesh* m, int a, int b, int c, int d) {
  m->faces.push_back({a, b, c});
  m->faces.push_back({a, c, d});
}

Mesh Cube() {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  AddQuad(&m, 0, 1, 3, 2);
  AddQuad(&m, 4, 5, 7, 6);
  AddQuad(&m, 0, 1, 5, 4);
  AddQuad(&m, 2, 3, 7, 6);
  AddQuad(&m, 0, 2, 6, 4);
  AddQuad(&m, 1, 3, 7, 5);
  OrientOutward(&m);
  return m;
}

Mesh Octahedron() {
  Mesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int x : {0, 1}) {
    for (int y : {2, 3}) {
      for (int z : {4, 5}) m.faces.push_back({x, y, z});
    }
  }
  OrientOutward(&m);
  return m;
}

Mesh Torus(int n, int k, double big_r = 2, double small_r = 0.5) {
  Mesh m;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / k;
      m.vertices.emplace_back((big_r + small_r * std::cos(v)) * std::cos(u),
                              (big_r + small_r * std::cos(v)) * std::sin(u), small_r * std::sin(v));
    }
  }
  auto id = [&](int i, int j) { return (i % n) * k + (j % k); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) AddQuad(&m, id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
  }
  return m;
}

Mesh UvSphere(int rings, int segments) {
  Mesh m;
  m.vertices.emplace_back(0, 0, 1);
  for (int r = 1; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const double theta = M_PI * r / rings, phi = 2 * M_PI * s / segments;
      m.vertices.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
    }
  }
  m.vertices.emplace_back(0, 0, -1);
  const int south = static_cast<int>(m.vertices.size()) - 1;
  auto id = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.faces.push_back({0, id(1, s), id(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r) {
    for (int s = 0; s < segments; ++s)
      AddQuad(&m, id(r, s), id(r + 1, s), id(r + 1, s + 1), id(r, s + 1));
  }
  for (int s = 0; s < segments; ++s)
    m.faces.push_back({south, id(rings - 1, s + 1), id(rings - 1, s)});
  return m;
}

MeshReport Check(const Mesh& m, bool allow_boundary = false) {
  MeshCheckOptions options;
  options.allow_boundary = allow_boundary;
  return CheckMesh(m, options);
}

// Every count except the ones named is zero.
void ExpectOnlyProblems(const MeshReport& r, std::set<std::string> expected) {
  const std::vector<std::pair<std::string, int64_t>> counts = {
      {"boundary_edges", r.num_boundary_edges},
      {"non_manifold_edges", r.num_non_manifold_edges},
      {"non_manifold_vertices", r.num_non_manifold_vertices},
      {"inconsistent_edges", r.num_inconsistent_edges},
      {"degenerate_faces", r.num_degenerate_faces},
      {"duplicate_faces", r.num_duplicate_faces},
      {"invalid_faces", r.num_invalid_faces},
      {"self_intersections", r.num_self_intersections}};
  for (const auto& [name, n] : counts) {
    if (expected.count(name)) {
      EXPECT_GT(n, 0) << name;
    } else {
      EXPECT_EQ(n, 0) << name;
    }
  }
}

TEST(MeshChecker, ClosedConvexSolidsAreValidGenusZero) {
  for (const auto& [name, mesh, v, e, f] :
       std::vector<std::tuple<std::string, Mesh, int, int, int>>{
           {"tetrahedron", Tetrahedron(), 4, 6, 4},
           {"cube", Cube(), 8, 18, 12},
           {"octahedron", Octahedron(), 6, 12, 8}}) {
    SCOPED_TRACE(name);
    const MeshReport r = Check(mesh);
    EXPECT_TRUE(r.is_closed_manifold);
    EXPECT_TRUE(r.is_valid);
    EXPECT_TRUE(r.Problems().empty());
    ExpectOnlyProblems(r, {});
    EXPECT_EQ(r.num_vertices, v);
    EXPECT_EQ(r.num_edges, e);
    EXPECT_EQ(r.num_faces, f);
    EXPECT_EQ(r.num_components, 1);
    EXPECT_EQ(r.euler_characteristic, 2);
    ASSERT_TRUE(r.genus.has_value());
    EXPECT_EQ(*r.genus, 0);
    ASSERT_EQ(r.components.size(), 1u);
    EXPECT_TRUE(r.components[0].oriented);
    ASSERT_TRUE(r.components[0].signed_volume.has_value());
    EXPECT_GT(*r.components[0].signed_volume, 0);  // outward normals
  }
  EXPECT_NEAR(*Check(Tetrahedron()).components[0].signed_volume, 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(*Check(Cube()).components[0].signed_volume, 1.0, 1e-12);
}

// A focused check tests only the pairs with a flagged face: the same crossing pairs as the full
// check when the flagged faces are those of a crossing tetrahedron, none when they are a far one's.
TEST(MeshChecker, FocusedCheckTestsOnlyPairsWithAFlaggedFace) {
  const Mesh a = test_meshes::Corner({0, 0, 0}, 1);
  const Mesh crossing = Append(a, test_meshes::Corner({0.2, 0.2, 0.2}, 1));
  const Mesh mesh = Append(crossing, test_meshes::Corner({10, 10, 10}, 1));
  MeshCheckOptions options;
  const MeshReport full = CheckMesh(mesh, options);
  ASSERT_GT(full.num_self_intersections, 0);
  options.focus_faces.assign(mesh.NumFaces(), 0);
  for (size_t f = 0; f < a.NumFaces(); ++f) options.focus_faces[f] = 1;
  const MeshReport first = CheckMesh(mesh, options);
  EXPECT_EQ(first.num_self_intersections, full.num_self_intersections);
  EXPECT_EQ(first.float_robustness.num_float_intersections,
            full.float_robustness.num_float_intersections);
  std::fill(options.focus_faces.begin(), options.focus_faces.end(), 0);
  for (size_t f = crossing.NumFaces(); f < mesh.NumFaces(); ++f) options.focus_faces[f] = 1;
  const MeshReport far = CheckMesh(mesh, options);
  EXPECT_EQ(far.num_self_intersections, 0);
  EXPECT_EQ(far.float_robustness.num_float_intersections, 0);
  EXPECT_EQ(far.float_robustness.num_close_face_pairs, 0);
  options.focus_faces.pop_back();
  EXPECT_THROW(CheckMesh(mesh, options), InputError);
}

TEST(MeshChecker, GeometryOnlyFindsTheSameGeometricProblems) {
  // Crossing corners (open, so topology has something to say too) and a degenerate face.
  Mesh mesh = Append(test_meshes::Corner({0, 0, 0}, 1), test_meshes::Corner({0.2, 0.2, 0.2}, 1));
  const int32_t v = static_cast<int32_t>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), {{5, 5, 5}, {6, 5, 5}, {7, 5, 5}});
  mesh.faces.push_back({v, v + 1, v + 2});
  MeshCheckOptions options;
  options.max_examples = 1000;
  const MeshReport full = CheckMesh(mesh, options);
  ASSERT_GT(full.num_boundary_edges, 0);
  ASSERT_GT(full.num_self_intersections, 0);
  ASSERT_EQ(full.num_degenerate_faces, 1);
  options.check_topology = false;
  const MeshReport geometry = CheckMesh(mesh, options);
  EXPECT_EQ(geometry.self_intersection_examples, full.self_intersection_examples);
  EXPECT_EQ(geometry.degenerate_face_examples, full.degenerate_face_examples);
  EXPECT_EQ(geometry.float_robustness.float_intersection_examples,
            full.float_robustness.float_intersection_examples);
  EXPECT_EQ(geometry.float_robustness.close_face_pair_examples,
            full.float_robustness.close_face_pair_examples);
  EXPECT_EQ(geometry.num_boundary_edges, 0);  // not looked at
  EXPECT_EQ(geometry.num_edges, 0);
}

TEST(MeshChecker, TorusHasGenusOne) {
  const MeshReport r = Check(Torus(12, 8));
  EXPECT_TRUE(r.is_valid);
  ExpectOnlyProblems(r, {});
  EXPECT_EQ(r.euler_characteristic, 0);
  ASSERT_TRUE(r.genus.has_value());
  EXPECT_EQ(*r.genus, 1);
}

TEST(MeshChecker, OpenSquareHasBoundaryAndIsValidOnlyWithAllowBoundary) {
  Mesh square;
  square.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  const MeshReport closed = Check(square);
  EXPECT_FALSE(closed.is_valid);
  EXPECT_FALSE(closed.is_closed_manifold);
  ExpectOnlyProblems(closed, {"boundary_edges"});
  EXPECT_EQ(closed.num_boundary_edges, 4);
  EXPECT_EQ(closed.num_boundary_vertices, 4);
  EXPECT_EQ(closed.euler_characteristic, 1);
  EXPECT_FALSE(closed.genus.has_value());
  using Edge = std::array<int32_t, 2>;
  EXPECT_THAT(closed.boundary_edge_examples,
              ElementsAre(Edge{0, 1}, Edge{0, 3}, Edge{1, 2}, Edge{2, 3}));
  const MeshReport open = Check(square, /*allow_boundary=*/true);
  EXPECT_TRUE(open.is_valid);
  EXPECT_FALSE(open.is_closed_manifold);
  EXPECT_THAT(open.ToTable(), HasSubstr("VALID 2-manifold with boundary"));
}

TEST(MeshChecker, VertexWithOpenFanIsABoundaryVertex) {
  // Fig. 1(b): an octahedron without one face; the three vertices around the hole have open
  // fans (their opposite edges form a path, not a closed cycle).
  Mesh m = Octahedron();
  m.faces.pop_back();
  const MeshReport r = Check(m);
  EXPECT_FALSE(r.is_valid);
  ExpectOnlyProblems(r, {"boundary_edges"});
  EXPECT_EQ(r.num_boundary_edges, 3);
  EXPECT_EQ(r.num_boundary_vertices, 3);
  EXPECT_EQ(r.num_non_manifold_vertices, 0);
  EXPECT_TRUE(Check(m, true).is_valid);
}

TEST(MeshChecker, TetrahedraSharingOnlyAVertexMakeANonManifoldVertex) {
  // Fig. 1(c): the edges opposite to the shared vertex form two cycles.
  Mesh m = Tetrahedron();
  const Mesh top = Tetrahedron(Eigen::Vector3d(0, 0, 1));
  m.vertices.insert(m.vertices.end(), top.vertices.begin() + 1, top.vertices.end());
  for (auto f : top.faces) {
    for (int32_t& v : f) v = v == 0 ? 3 : v + 3;  // top's vertex 0 is our vertex 3
    m.faces.push_back(f);
  }
  const MeshReport r = Check(m);
  EXPECT_FALSE(r.is_valid);
  ExpectOnlyProblems(r, {"non_manifold_vertices"});
  EXPECT_EQ(r.num_non_manifold_vertices, 1);
  EXPECT_THAT(r.non_manifold_vertex_examples, ElementsAre(3));
  EXPECT_EQ(r.num_components, 1);
  EXPECT_FALSE(r.genus.has_value());
  // Still invalid when boundaries are allowed: two fans are not a boundary.
  EXPECT_FALSE(Check(m, true).is_valid);
}

// Unreferenced vertices go, the others are renumbered in order of first use, colours follow;
// FacesWithoutFlaggedVertices keeps the faces with no flagged vertex, in order, the same way.
TEST(Mesh, UnreferencedVerticesGoAndTheRestKeepTheirFirstUseOrder) {
  Mesh m;
  for (int i = 0; i < 6; ++i) {
    m.vertices.push_back(Eigen::Vector3d(i, 0, 0));
    m.vertex_colors.push_back({static_cast<uint8_t>(i), 0, 0});
  }
  m.faces = {{4, 2, 5}, {5, 2, 0}};  // 1 and 3 unused
  Mesh r = m;
  r.RemoveUnreferencedVertices();
  ASSERT_EQ(r.vertices.size(), 4u);
  EXPECT_EQ(r.faces, (std::vector<std::array<int32_t, 3>>{{0, 1, 2}, {2, 1, 3}}));
  EXPECT_EQ(r.vertices[0].x(), 4);
  EXPECT_EQ(r.vertices[3].x(), 0);
  EXPECT_EQ(r.vertex_colors[1][0], 2);
  std::vector<uint8_t> flagged(6, 0);
  flagged[4] = 1;
  const Mesh without = FacesWithoutFlaggedVertices(m, flagged);
  EXPECT_EQ(without.faces, (std::vector<std::array<int32_t, 3>>{{0, 1, 2}}));
  ASSERT_EQ(without.vertices.size(), 3u);
  EXPECT_EQ(without.vertices[0].x(), 5);
  EXPECT_EQ(without.vertices[2].x(), 0);
  EXPECT_EQ(without.vertex_colors[1][0], 2);
  EXPECT_EQ(m.vertices.size(), 6u);  // the source is left as it was
}

// What FacesWithoutFlaggedVertices does where dropping faces leaves a bow-tie: the larger fan
// stays (here equal: the first), and the result passes the checker with boundaries allowed.
TEST(KeepOneFanPerVertex, SplitsABowTieLeavingAValidSurfaceWithBoundary) {
  Mesh m = Tetrahedron();
  const Mesh top = Tetrahedron(Eigen::Vector3d(0, 0, 1));
  m.vertices.insert(m.vertices.end(), top.vertices.begin() + 1, top.vertices.end());
  for (auto f : top.faces) {
    for (int32_t& v : f) v = v == 0 ? 3 : v + 3;
    m.faces.push_back(f);
  }
  EXPECT_EQ(KeepOneFanPerVertex(&m), 3);  // the top tetrahedron's faces at the shared vertex
  ASSERT_EQ(m.faces.size(), 5u);          // the bottom tetrahedron and the top's far face
  const MeshReport r = Check(m, true);
  EXPECT_TRUE(r.is_valid) << r.ToTable();
  EXPECT_EQ(r.num_components, 2);
  EXPECT_EQ(r.num_boundary_edges, 3);
  EXPECT_EQ(KeepOneFanPerVertex(&m), 0);  // nothing left to split
  // A closed 2-manifold keeps every face.
  Mesh closed = Octahedron();
  EXPECT_EQ(KeepOneFanPerVertex(&closed), 0);
  EXPECT_EQ(closed.faces.size(), 8u);
  EXPECT_TRUE(Check(closed).is_valid);
}

TEST(MeshChecker, ThreeFacesOnAnEdgeMakeANonManifoldEdge) {
  Mesh m = Tetrahedron();
  m.vertices.emplace_back(0.5, -1, 0.5);
  m.faces.push_back({0, 1, 4});  // a fin on edge 0-1, outside the tetrahedron
  const MeshReport r = Check(m, /*allow_boundary=*/true);
  EXPECT_FALSE(r.is_valid);
  ExpectOnlyProblems(r, {"boundary_edges", "non_manifold_edges", "non_manifold_vertices"});
  EXPECT_EQ(r.num_non_manifold_edges, 1);
  EXPECT_THAT(r.non_manifold_edge_examples, ElementsAre(std::array<int32_t, 2>{0, 1}));
  EXPECT_EQ(r.num_boundary_edges, 2);
  EXPECT_THAT(r.non_manifold_vertex_examples, ElementsAre(0, 1));
}

TEST(MeshChecker, OneFlippedFaceIsAnOrientationError) {
  Mesh m = Tetrahedron();
  std::swap(m.faces[3][1], m.faces[3][2]);
  const MeshReport r = Check(m);
  EXPECT_FALSE(r.is_valid);
  ExpectOnlyProblems(r, {"inconsistent_edges"});
  EXPECT_EQ(r.num_inconsistent_edges, 3);
  ASSERT_EQ(r.components.size(), 1u);
  EXPECT_FALSE(r.components[0].oriented);
  EXPECT_TRUE(r.components[0].orientable);
  EXPECT_EQ(r.components[0].genus, 0);  // topology is fine, only the orientation is not
  EXPECT_FALSE(r.components[0].signed_volume.has_value());
}

TEST(MeshChecker, MobiusStripIsNotOrientable) {
  const int n = 10;
  Mesh m;
  for (int i = 0; i < n; ++i) {
    const double u = 2 * M_PI * i / n;
    const Eigen::Vector3d c(2 * std::cos(u), 2 * std::sin(u), 0);
    const Eigen::Vector3d d(std::cos(u / 2) * std::cos(u), std::cos(u / 2) * std::sin(u),
                            std::sin(u / 2));
    m.vertices.push_back(c + 0.5 * d);  // 2i: top
    m.vertices.push_back(c - 0.5 * d);  // 2i+1: bottom
  }
  for (int i = 0; i < n; ++i) {
    const int t = 2 * i, b = 2 * i + 1;
    // After a full turn the strip comes back upside down: top meets bottom.
    const int t1 = i + 1 < n ? 2 * (i + 1) : 1, b1 = i + 1 < n ? 2 * (i + 1) + 1 : 0;
    AddQuad(&m, t, b, b1, t1);
  }
  const MeshReport r = Check(m, /*allow_boundary=*/true);
  EXPECT_FALSE(r.is_valid);
  ExpectOnlyProblems(r, {"boundary_edges", "inconsistent_edges"});
  ASSERT_EQ(r.components.size(), 1u);
  EXPECT_FALSE(r.components[0].orientable);
  EXPECT_EQ(r.euler_characteristic, 0);
}

TEST(MeshChecker, DegenerateFaces) {
  Mesh repeated = Tetrahedron();
  repeated.faces.push_back({0, 0, 1});
  MeshReport r = Check(repeated);
  EXPECT_FALSE(r.is_valid);
  ExpectOnlyProblems(r, {"degenerate_faces"});
  EXPECT_THAT(r.degenerate_face_examples, ElementsAre(4));

  // Zero area with three distinct vertices, found exactly: a flat sliver on a line.
  Mesh flat = Tetrahedron();
  flat.vertices.emplace_back(0.1, 0.2, 0.3);
  flat.vertices.emplace_back(0.1 + 1.0 / 3.0, 0.2, 0.3);
  flat.vertices.emplace_back(0.1 + 2.0 / 3.0, 0.2, 0.3);
  flat.faces.push_back({4, 5, 6});
  r = Check(flat, true);
  EXPECT_EQ(r.num_degenerate_faces, 1);
  EXPECT_THAT(r.degenerate_face_examples, ElementsAre(4));
  EXPECT_FALSE(r.is_valid);
}

TEST(MeshChecker, DuplicateFaces) {
  for (const Face& extra : {Face{0, 2, 1}, Face{1, 0, 2}, Face{0, 1, 2}}) {
    Mesh m = Tetrahedron();
    m.faces.push_back(extra);
    const MeshReport r = Check(m);
    EXPECT_FALSE(r.is_valid);
    EXPECT_EQ(r.num_duplicate_faces, 1);
    EXPECT_THAT(r.duplicate_face_examples, ElementsAre(4));
    EXPECT_EQ(r.num_non_manifold_edges, 3);
    EXPECT_EQ(r.num_self_intersections, 0);  // the same triangle is reported as a duplicate
  }
}

TEST(MeshChecker, InterpenetratingTetrahedraSelfIntersect) {
  const Mesh m = Append(Tetrahedron(), Tetrahedron(Eigen::Vector3d(0.2, 0.2, 0.2)));
  const MeshReport r = Check(m);
  EXPECT_FALSE(r.is_valid);
  ExpectOnlyProblems(r, {"self_intersections"});
  EXPECT_GT(r.num_self_intersections, 0);
  EXPECT_EQ(r.num_components, 2);
  for (const auto& pair : r.self_intersection_examples) {
    EXPECT_LT(pair[0], 4);  // one face from each tetrahedron
    EXPECT_GE(pair[1], 4);
  }
  // Switched off, the mesh passes (the report says it was not checked).
  MeshCheckOptions options;
  options.check_self_intersections = false;
  const MeshReport unchecked = CheckMesh(m, options);
  EXPECT_TRUE(unchecked.is_valid);
  EXPECT_FALSE(unchecked.self_intersections_checked);
  EXPECT_THAT(unchecked.ToTable(), HasSubstr("not checked"));
  // The search stops at the limit.
  options.check_self_intersections = true;
  options.max_self_intersections = 1;
  const MeshReport limited = CheckMesh(m, options);
  EXPECT_EQ(limited.num_self_intersections, 1);
  EXPECT_TRUE(limited.self_intersections_truncated);
}

TEST(MeshChecker, TouchingAndFoldedPairs) {
  // Shared vertex, the other triangle's opposite edge pierces the first.
  Mesh pierce;
  pierce.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -1}, {0.2, 0.2, 1}};
  pierce.faces = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(Check(pierce, true).num_self_intersections, 1);
  // Shared vertex only, apart: no intersection.
  Mesh apart = pierce;
  apart.vertices[3] = {-0.2, -0.2, -1};
  apart.vertices[4] = {-0.2, -0.2, 1};
  EXPECT_EQ(Check(apart, true).num_self_intersections, 0);
  // Shared edge, folded flat onto each other: intersection; unfolded flat: none.
  Mesh folded;
  folded.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.3, 0}};
  folded.faces = {{0, 1, 2}, {1, 0, 3}};
  EXPECT_EQ(Check(folded, true).num_self_intersections, 1);
  folded.vertices[3] = {0.3, -0.5, 0};
  EXPECT_EQ(Check(folded, true).num_self_intersections, 0);
  // A vertex (another index) touching the inside of a face counts.
  Mesh touch;
  touch.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, 0}, {0.2, 0.2, 1}, {1, 1, 1}};
  touch.faces = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(Check(touch, true).num_self_intersections, 1);
}

TEST(MeshChecker, ClosedMeshWithTwoComponents) {
  const Mesh m = Append(Tetrahedron(), Tetrahedron(Eigen::Vector3d(5, 0, 0)));
  const MeshReport r = Check(m);
  EXPECT_TRUE(r.is_valid);
  EXPECT_EQ(r.num_components, 2);
  EXPECT_EQ(r.euler_characteristic, 4);
  EXPECT_EQ(r.genus, 0);
  EXPECT_THAT(r.ToTable(), HasSubstr("components (largest first)"));
}

TEST(MeshChecker, EmptyInvalidAndUnreferenced) {
  EXPECT_FALSE(Check(Mesh{}).is_valid);
  EXPECT_THAT(Check(Mesh{}).Problems(), ElementsAre(HasSubstr("no faces")));

  Mesh m = Tetrahedron();
  m.vertices.emplace_back(9, 9, 9);  // unreferenced: reported, allowed
  MeshReport r = Check(m);
  EXPECT_TRUE(r.is_valid);
  EXPECT_EQ(r.num_unreferenced_vertices, 1);
  EXPECT_THAT(r.unreferenced_vertex_examples, ElementsAre(4));

  m.faces.push_back({0, 1, 7});  // out of range
  m.vertices.emplace_back(NAN, 0, 0);
  m.faces.push_back({0, 1, 5});  // non-finite vertex
  r = Check(m);
  EXPECT_FALSE(r.is_valid);
  EXPECT_EQ(r.num_invalid_faces, 2);
  EXPECT_THAT(r.invalid_face_examples, ElementsAre(4, 5));

  MeshCheckOptions bad;
  bad.max_examples = -1;
  EXPECT_THROW(CheckMesh(m, bad), InputError);
}

TEST(MeshChecker, JsonHasTheCountsAndExamples) {
  Mesh m = Tetrahedron();
  std::swap(m.faces[3][1], m.faces[3][2]);
  const nlohmann::json j = nlohmann::json::parse(Check(m).ToJson("t.ply"));
  EXPECT_EQ(j["source"], "t.ply");
  EXPECT_EQ(j["valid"], false);
  EXPECT_EQ(j["faces"], 4);
  EXPECT_EQ(j["inconsistent_edges"], 3);
  EXPECT_EQ(j["examples"]["inconsistent_edges"].size(), 3u);
  EXPECT_EQ(j["genus"], 0);
  EXPECT_EQ(j["component_list"][0]["oriented"], false);
  EXPECT_EQ(j["problems"].size(), 1u);
  EXPECT_TRUE(j["component_list"][0]["signed_volume"].is_null());
}

// An independent oracle: CGAL's own self_intersections on a Surface_mesh must find exactly the
// same face pairs on a valid (manifold) mesh made to fold through itself.
TEST(MeshChecker, SelfIntersectionsMatchCgalPolygonMeshProcessing) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 0.12);
  int meshes_with_intersections = 0;
  for (int trial = 0; trial < 5; ++trial) {
    Mesh m = UvSphere(10, 16);
    for (auto& v : m.vertices) v += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    MeshCheckOptions options;
    options.max_examples = 1 << 20;
    const MeshReport r = CheckMesh(m, options);
    ASSERT_EQ(r.num_non_manifold_vertices, 0);
    ASSERT_EQ(r.num_degenerate_faces, 0);

    std::vector<Kernel::Point_3> points;
    for (const auto& v : m.vertices) points.emplace_back(v.x(), v.y(), v.z());
    std::vector<std::vector<std::size_t>> polygons;
    for (const auto& f : m.faces) polygons.push_back({size_t(f[0]), size_t(f[1]), size_t(f[2])});
    SurfaceMesh sm;
    PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
    ASSERT_EQ(sm.number_of_faces(), m.faces.size());
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
    PMP::self_intersections(sm, std::back_inserter(pairs));
    std::set<std::array<int64_t, 2>> expected;
    for (const auto& [a, b] : pairs) {
      const int64_t x = static_cast<int64_t>(a.idx()), y = static_cast<int64_t>(b.idx());
      expected.insert({std::min(x, y), std::max(x, y)});
    }
    const std::set<std::array<int64_t, 2>> found(r.self_intersection_examples.begin(),
                                                 r.self_intersection_examples.end());
    EXPECT_EQ(found, expected) << "trial " << trial;
    EXPECT_EQ(r.num_self_intersections, static_cast<int64_t>(expected.size()));
    if (!expected.empty()) ++meshes_with_intersections;
  }
  EXPECT_GE(meshes_with_intersections, 3);  // the noise really folds the spheres
}

}  // namespace
}  // namespace ms
