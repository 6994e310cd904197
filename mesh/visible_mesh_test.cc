#include "mesh/visible_mesh.h"

#include <gtest/gtest.h>

#include "base/error.h"

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

}  // namespace
}  // namespace ms
