#include "mesh/visible_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "base/error.h"
#include "base/parallel_for.h"

namespace ms {
namespace {

// Camera at (0, 0, 5) looking down -z (image x = world x, image y = world -y).
View DownView() {
  View v;
  v.intrinsics = {100, 80, 100, 100, 50, 40};
  v.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  v.SetCenter({0, 0, 5});
  return v;
}

// A triangle in the plane z = `z` near (x, y), counter-clockwise seen from +z if `up`.
void AddTriangle(Mesh* mesh, double x, double y, double z, bool up) {
  const int32_t base = static_cast<int32_t>(mesh->vertices.size());
  mesh->vertices.emplace_back(x, y, z);
  mesh->vertices.emplace_back(x + 0.2, y, z);
  mesh->vertices.emplace_back(x, y + 0.2, z);
  if (up) {
    mesh->faces.push_back({base, base + 1, base + 2});
  } else {
    mesh->faces.push_back({base, base + 2, base + 1});
  }
}

TEST(ExtractVisibleMesh, KeepsFacingFacesInsideTheFrustum) {
  Mesh mesh;
  AddTriangle(&mesh, 0, 0, 0, true);       // 0: visible
  AddTriangle(&mesh, 0.5, 0.5, 0, false);  // 1: back-facing
  AddTriangle(&mesh, 10, 0, 0, true);      // 2: far right of the image (u ~ 250)
  AddTriangle(&mesh, 0, 0, 6, true);       // 3: behind the camera
  AddTriangle(&mesh, -0.5, 0.3, 1, true);  // 4: visible
  AddTriangle(&mesh, 0, -12, 0, true);     // 5: below the image
  // 6: straddles the left border (two corners outside): kept.
  mesh.vertices.emplace_back(-2.6, 0, 0);
  mesh.vertices.emplace_back(-2.4, 0, 0);
  mesh.vertices.emplace_back(-2.6, 0.2, 0);
  mesh.faces.push_back({18, 19, 20});
  mesh.vertex_colors.assign(mesh.vertices.size(), {1, 2, 3});
  mesh.vertex_colors[12] = {9, 9, 9};

  const VisibleMesh visible = ExtractVisibleMesh(mesh, DownView());
  EXPECT_EQ(visible.face_ids, (std::vector<int32_t>{0, 4, 6}));
  ASSERT_EQ(visible.mesh.NumFaces(), 3u);
  ASSERT_EQ(visible.mesh.NumVertices(), 9u);
  EXPECT_EQ(visible.vertex_ids, (std::vector<int32_t>{0, 1, 2, 12, 13, 14, 18, 19, 20}));
  for (size_t f = 0; f < visible.mesh.NumFaces(); ++f) {
    for (int i = 0; i < 3; ++i) {
      const int32_t v = visible.mesh.faces[f][i];
      EXPECT_EQ(visible.mesh.vertices[v], mesh.vertices[mesh.faces[visible.face_ids[f]][i]]);
    }
  }
  EXPECT_EQ(visible.mesh.vertex_colors[3], (std::array<uint8_t, 3>{9, 9, 9}));

  VisibleMeshOptions keep_back;
  keep_back.keep_back_facing = true;
  EXPECT_EQ(ExtractVisibleMesh(mesh, DownView(), keep_back).face_ids,
            (std::vector<int32_t>{0, 1, 4, 6}));
  // A margin wide enough brings the face at u ~ 250 in (the triangle spans u 250..254).
  VisibleMeshOptions margin;
  margin.margin_px = 160;
  EXPECT_EQ(ExtractVisibleMesh(mesh, DownView(), margin).face_ids,
            (std::vector<int32_t>{0, 2, 4, 6}));
  // A near plane at depth 4.5 removes the face at height 1 (depth 4), keeps those at depth 5.
  VisibleMeshOptions near;
  near.near = 4.5;
  EXPECT_EQ(ExtractVisibleMesh(mesh, DownView(), near).face_ids, (std::vector<int32_t>{0, 6}));
}

TEST(ExtractVisibleMesh, FaceCrossingTheCameraPlaneIsKept) {
  // One corner behind the camera, two in front and inside the image.
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {0.2, 0, 0}, {0.1, 0.1, 7}};
  mesh.faces = {{0, 1, 2}};
  const View view = DownView();
  EXPECT_TRUE(TriangleInFrustum(view, mesh.vertices[0], mesh.vertices[1], mesh.vertices[2]));
}

TEST(ExtractVisibleMesh, DegenerateFacesAndBadIndices) {
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {0.1, 0, 0}, {0.2, 0, 0}};
  mesh.faces = {{0, 1, 2}};
  EXPECT_EQ(ExtractVisibleMesh(mesh, DownView()).mesh.NumFaces(), 0u);
  mesh.faces = {{0, 1, 3}};
  EXPECT_THROW(ExtractVisibleMesh(mesh, DownView()), InputError);
  VisibleMeshOptions bad;
  bad.margin_px = -1;
  EXPECT_THROW(bad.Check(), InputError);
}

// A wavy terrain of 120 x 120 vertices (28,322 faces) in shuffled face order, so that blocks
// are not simply runs of the input.
Mesh Terrain() {
  Mesh mesh;
  const int n = 120;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      mesh.vertices.emplace_back(i * 0.1, j * 0.1, 0.3 * std::sin(i * 0.21) * std::cos(j * 0.17));
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int32_t v = j * n + i;
      mesh.faces.push_back({v, v + 1, v + n + 1});
      mesh.faces.push_back({v, v + n + 1, v + n});
    }
  }
  std::mt19937 rng(7);
  std::shuffle(mesh.faces.begin(), mesh.faces.end(), rng);
  return mesh;
}

// A camera at `centre` looking at `target` (y roughly down the image).
View LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  View v;
  v.intrinsics = {640, 480, 500, 500, 320, 240};
  const Eigen::Vector3d z = (target - centre).normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  v.R.row(0) = x;
  v.R.row(1) = y;
  v.R.row(2) = z;
  v.SetCenter(centre);
  return v;
}

TEST(VisibleMeshIndex, ExtractsExactlyWhatTheFaceByFaceTestKeeps) {
  const Mesh mesh = Terrain();
  const VisibleMeshIndex index(mesh);
  EXPECT_EQ(index.num_blocks(), (mesh.faces.size() + 31) / 32);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> across(-3, 15), height(-1, 6);
  VisibleMeshOptions wide;
  wide.margin_px = 40;
  wide.near = 0.5;
  VisibleMeshOptions both_sides;
  both_sides.keep_back_facing = true;
  int64_t kept = 0, partial = 0;
  for (int camera = 0; camera < 60; ++camera) {
    const View view = LookAt({across(rng), across(rng), height(rng)},
                             {across(rng), across(rng), height(rng) - 2});
    for (const VisibleMeshOptions& options : {VisibleMeshOptions(), wide, both_sides}) {
      const VisibleMesh expected = ExtractVisibleMesh(mesh, view, options);
      const VisibleMesh got = index.Extract(view, options);
      ASSERT_EQ(got.face_ids, expected.face_ids) << "camera " << camera;
      ASSERT_EQ(got.vertex_ids, expected.vertex_ids) << "camera " << camera;
      ASSERT_EQ(got.mesh.faces, expected.mesh.faces);
      ASSERT_EQ(got.mesh.vertices, expected.mesh.vertices);
      kept += static_cast<int64_t>(got.face_ids.size());
      partial += !got.face_ids.empty() && got.face_ids.size() < mesh.faces.size();
    }
  }
  // The cameras see parts of the terrain: the blocks are really culled, not all kept or none.
  EXPECT_GT(partial, 60);
  EXPECT_GT(kept, 0);
}

TEST(VisibleMeshIndex, GivesTheSameResultFromManyThreads) {
  const Mesh mesh = Terrain();
  const VisibleMeshIndex index(mesh);
  std::vector<View> views;
  for (int c = 0; c < 32; ++c) views.push_back(LookAt({c * 0.4, -2, 4}, {c * 0.4, 6, 0}));
  std::vector<VisibleMesh> got(views.size());
  ParallelFor(
      views.size(), [&](size_t c) { got[c] = index.Extract(views[c]); }, 4);
  for (size_t c = 0; c < views.size(); ++c) {
    EXPECT_EQ(got[c].face_ids, ExtractVisibleMesh(mesh, views[c]).face_ids) << "camera " << c;
  }
}

TEST(VisibleMeshIndex, RefusesBadIndicesAndTakesAnEmptyMesh) {
  Mesh mesh;
  AddTriangle(&mesh, 0, 0, 0, true);
  mesh.faces.push_back({0, 1, 7});
  EXPECT_THROW(VisibleMeshIndex{mesh}, InputError);
  const Mesh empty;
  EXPECT_TRUE(VisibleMeshIndex(empty).Extract(DownView()).face_ids.empty());
}

}  // namespace
}  // namespace ms
