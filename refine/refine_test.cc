#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <type_traits>
#include <vector>

#include "base/error.h"
#include "gl/context.h"
#include "mesh/float_robustness.h"
#include "mesh/mesh_checker.h"
#include "refine/gradient_kernel.h"
#include "refine/mesh_moves.h"
#include "refine/pair_sampling.h"
#include "refine/photometric_gradient.h"
#include "refine/refine_wire.h"
#include "refine/refiner.h"
#include "refine/remesh.h"
#include "testing/sweep_test_scene.h"
#include "testing/test_meshes.h"

namespace ms {
namespace {

// The pyramid scene's camera pairs: camera 0 with each neighbour, and back.
const std::vector<std::pair<int, int>> kPyramidPairs = {{0, 1}, {0, 2}, {1, 0}, {2, 0}};

// The pyramid scene's true surface (open: a ring of ground) with its apex at `fraction` of its
// height.
Mesh LoweredApex(const PyramidScene& scene, double fraction) {
  Mesh mesh = scene.truth;
  mesh.vertices[0].z() = scene.pyramid_height * fraction;
  return mesh;
}

// check-mesh's verdict, boundaries allowed (the pyramid scene's surface is open).
bool ValidWithBoundary(const Mesh& mesh) {
  MeshCheckOptions check;
  check.allow_boundary = true;
  return CheckMesh(mesh, check).is_valid;
}

void ExpectSameVertices(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t v = 0; v < a.vertices.size(); ++v) EXPECT_EQ(a.vertices[v], b.vertices[v]);
}

RefineView NoiseView(const View& view, uint64_t seed) {
  RefineView out;
  out.view = view;
  BlurredNoiseImage(view.intrinsics.width, view.intrinsics.height, seed)
      .convertTo(out.image, CV_64F);
  return out;
}

// A bumpy 8 x 8 grid over [-1, 1]^2 (z up to 0.05), so no two faces are coplanar.
Mesh BumpyGrid() {
  Mesh mesh = MakeFlatSquare(0, 1, 8);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    mesh.vertices[v].z() = 0.05 * std::sin(1.7 * v) * std::cos(0.9 * v);
  }
  return mesh;
}

double PairEnergy(const Mesh& mesh, const RefineView& a, const RefineView& b,
                  const RefineOptions& options) {
  return ComputePairGradientReference(mesh, a, b, options).energy;
}

// The analytic gradient is the derivative of the energy the same function computes: central
// differences over vertices in the middle of the image, along x, y and z. The reference's (in
// double: the fast kernel's float maps are too coarse for differences of 1e-7).
TEST(PhotometricGradient, MatchesFiniteDifferencesOfTheEnergy) {
  // Off axis: from (0, 0, 3) the grid's diagonal edges project onto rows of pixel centres,
  // where the energy has a kink (each such pixel changes face as a vertex moves).
  const RefineView a = NoiseView(LookAtView({0.03, -0.02, 3}, {0.01, 0.02, 0}, 160, 120, 150), 1);
  const RefineView b = NoiseView(LookAtView({0.6, 0.1, 2.9}, {0, 0, 0}, 160, 120, 150), 2);
  RefineOptions options;
  options.gaussian_sigma_px = 2;
  const Mesh mesh = BumpyGrid();
  const PairGradient g = ComputePairGradientReference(mesh, a, b, options);
  ASSERT_GT(g.pixels, 5000);
  const double h = 1e-7;
  int checked = 0;
  for (int v : {30, 40, 41, 49}) {  // interior vertices of the 9 x 9 grid
    ASSERT_GT(g.weight[v], 10);
    for (int axis = 0; axis < 3; ++axis) {
      Mesh plus = mesh, minus = mesh;
      plus.vertices[v][axis] += h;
      minus.vertices[v][axis] -= h;
      const double numeric =
          (PairEnergy(plus, a, b, options) - PairEnergy(minus, a, b, options)) / (2 * h);
      const double analytic = g.gradient[v][axis];
      EXPECT_NEAR(analytic, numeric, 1e-3 * std::abs(numeric) + 1e-3)
          << "vertex " << v << " axis " << axis;
      ++checked;
    }
    // Moving a vertex along a face's plane changes no depth: the gradient is not zero only
    // because the faces around it are not coplanar; it is never tangential to all of them.
    EXPECT_GT(g.gradient[v].norm(), 0);
  }
  EXPECT_EQ(checked, 12);
}

// Sum over vertices of |x - y| against the sum of |y|, for per-vertex quantities.
template <typename T>
double RelativeL1(const std::vector<T>& x, const std::vector<T>& y) {
  double difference = 0, size = 0;
  for (size_t v = 0; v < x.size(); ++v) {
    if constexpr (std::is_same_v<T, double>) {
      difference += std::abs(x[v] - y[v]);
      size += std::abs(y[v]);
    } else {
      difference += (x[v] - y[v]).norm();
      size += y[v].norm();
    }
  }
  return difference / size;
}

// The fast kernel computes the reference's sums in float maps: the same pixels (bar a few where
// float 1/z decides between two faces), energies and gradients equal to float rounding; the
// bounds sit a few times above the measured differences, so a wrong factor anywhere fails.
// How far a kernel may be from the reference on the agreement scenes.
struct KernelBounds {
  int64_t pixels;
  double energy, gradient, parallax, weight;
};

// A kernel against the reference on a bumpy grid and on the pyramid with its apex lowered (so
// the gradient is not zero), at window sizes below, at and above the default.
void ExpectAgreesWithTheReference(PairGradientKernel& kernel, const KernelBounds& bounds) {
  struct Case {
    const char* name;
    Mesh mesh;
    RefineView a, b;
  };
  const PyramidScene pyramid = MakePyramidScene();
  const std::vector<Case> cases = {
      {"bumpy grid", BumpyGrid(),
       NoiseView(LookAtView({0.03, -0.02, 3}, {0.01, 0.02, 0}, 160, 120, 150), 1),
       NoiseView(LookAtView({0.6, 0.1, 2.9}, {0, 0, 0}, 160, 120, 150), 2)},
      {"pyramid, apex lowered", LoweredApex(pyramid, 2.0 / 3),
       RefineViewAtLevel(pyramid.cameras[0], 0), RefineViewAtLevel(pyramid.cameras[1], 0)},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    for (double sigma : {1.0, 2.0, 4.5}) {
      RefineOptions options;
      options.gaussian_sigma_px = sigma;
      const PairGradient ref = ComputePairGradientReference(c.mesh, c.a, c.b, options);
      const PairGradient got = kernel.Compute(c.mesh, c.a, c.b, options);
      ASSERT_GT(ref.pixels, 5000);
      EXPECT_LE(std::abs(got.pixels - ref.pixels), bounds.pixels) << "sigma " << sigma;
      EXPECT_NEAR(got.energy / ref.energy, 1, bounds.energy) << "sigma " << sigma;
      EXPECT_LT(RelativeL1(got.gradient, ref.gradient), bounds.gradient) << "sigma " << sigma;
      EXPECT_LT(RelativeL1(got.parallax_rate2, ref.parallax_rate2), bounds.parallax)
          << "sigma " << sigma;
      EXPECT_LT(RelativeL1(got.weight, ref.weight), bounds.weight) << "sigma " << sigma;
      for (size_t v = 0; v < got.weight.size(); ++v) {  // what the coordinator accepts
        ASSERT_GE(got.weight[v], 0) << "vertex " << v;
        ASSERT_GE(got.parallax_rate2[v], 0) << "vertex " << v;
      }
    }
  }
}

// The fast kernel stores in float what the reference computes in double; the bounds below
// leave room above that rounding.
TEST(PhotometricGradient, FastKernelAgreesWithTheReference) {
  const std::unique_ptr<PairGradientKernel> fast = MakePairGradientKernel("cpu");
  ExpectAgreesWithTheReference(*fast, {10, 5e-5, 1e-4, 1e-7, 1e-12});
}

// The GLSL kernel on this machine's GL (llvmpipe without a GPU): GL's own rasteriser, rays,
// projections and barycentric weights in float, so its bounds are looser than the fast
// kernel's.
TEST(PhotometricGradient, GlslKernelAgreesWithTheReference) {
  const std::unique_ptr<PairGradientKernel> glsl = MakePairGradientKernel("glsl");
  ASSERT_EQ(glsl->Name(), "refine-glsl");
  ExpectAgreesWithTheReference(*glsl, {10, 1e-4, 1e-4, 5e-5, 1e-6});
}

// Inside the face the weights are the point's own; a rounding error outside, they are clamped
// onto the face, never negative, and still sum to 1 (a default reconstruct of the downward
// pyramid had its workers sent away for a vertex whose summed weight came out negative).
TEST(PhotometricGradient, BarycentricWeightsStayOnTheFace) {
  const std::array<double, 3> inside = BarycentricOnFace(0.2, 0.3);
  EXPECT_DOUBLE_EQ(inside[0], 0.2);
  EXPECT_DOUBLE_EQ(inside[1], 0.3);
  EXPECT_DOUBLE_EQ(inside[2], 0.5);
  for (const auto& [phi0, phi1] : {std::pair{-1e-9, 0.4}, std::pair{0.7, 0.3 + 1e-9},
                                   std::pair{1 + 1e-7, -1e-7}, std::pair{-1e-9, -1e-9}}) {
    const std::array<double, 3> w = BarycentricOnFace(phi0, phi1);
    for (double x : w) EXPECT_GE(x, 0);
    EXPECT_NEAR(w[0] + w[1] + w[2], 1, 1e-15);
    EXPECT_NEAR(w[0], std::max(phi0, 0.0), 1e-6);
  }
}

// "auto" takes the GPU only where there is one: on a software rasteriser the fast CPU kernel.
TEST(PhotometricGradient, KernelChoice) {
  std::string why;
  const std::unique_ptr<PairGradientKernel> chosen = MakePairGradientKernel("auto", &why);
  const gl::GlContext probe;
  EXPECT_EQ(chosen->Name(), probe.info().software ? "refine-fast-cpu" : "refine-glsl") << why;
  EXPECT_NE(why, "");
  EXPECT_EQ(MakePairGradientKernel("reference")->Name(), "refine-reference");
  EXPECT_THROW(MakePairGradientKernel("cuda"), InputError);
  RefineOptions options;
  options.kernel = "cuda";
  EXPECT_THROW(options.Check(), InputError);
}

// The thin-plate gradient is the derivative of 1/2 sum |L(v)|^2.
TEST(MeshMoves, ThinPlateGradientMatchesFiniteDifferences) {
  const Mesh mesh = BumpyGrid();
  const auto neighbours = VertexNeighbours(mesh);
  const auto energy = [&](const Mesh& m) {
    double e = 0;
    for (size_t v = 0; v < m.vertices.size(); ++v) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int32_t u : neighbours[v]) mean += m.vertices[u];
      e += 0.5 * (mean / neighbours[v].size() - m.vertices[v]).squaredNorm();
    }
    return e;
  };
  const auto gradient = ThinPlateGradient(mesh, neighbours);
  for (int v : {0, 5, 40}) {
    for (int axis = 0; axis < 3; ++axis) {
      Mesh plus = mesh, minus = mesh;
      plus.vertices[v][axis] += 1e-6;
      minus.vertices[v][axis] -= 1e-6;
      EXPECT_NEAR(gradient[v][axis], (energy(plus) - energy(minus)) / 2e-6, 1e-6);
    }
  }
}

// A sheet lifted through a camera's centre stops short of it by the clearance where it lies
// under it; lowered, away from it, it moves freely, and without the camera the lift goes through.
TEST(MeshMoves, TheSurfaceKeepsClearOfTheCameras) {
  const Mesh start = MakeFlatSquare(0, 1, 4);  // vertex 12 at the centre
  ASSERT_EQ(start.vertices[12], Eigen::Vector3d(0, 0, 0));
  const Eigen::Vector3d camera(0, 0, 0.05);
  const auto moved = [&](double dz, bool with_camera) {
    Mesh mesh = start;
    MoveOptions options;
    options.tolerance = 1e-6;
    if (with_camera) {
      options.keep_clear = {camera};
      options.clearance = 0.02;
    }
    MoveVerticesSafely(&mesh, std::vector<Eigen::Vector3d>(mesh.vertices.size(), {0, 0, dz}),
                       options);
    EXPECT_TRUE(ValidWithBoundary(mesh));
    return mesh;
  };
  const Mesh lifted = moved(0.1, true);
  EXPECT_GT(lifted.vertices[12].z(), 0);  // halved: 0.1 and 0.05 cross it or come too near
  EXPECT_LE(lifted.vertices[12].z(), camera.z() - 0.02);
  EXPECT_EQ(lifted.vertices[0].z(), 0.1);  // a corner, far from the camera
  EXPECT_EQ(moved(-0.1, true).vertices[12].z(), -0.1);
  EXPECT_EQ(moved(0.1, false).vertices[12].z(), 0.1);
}

// A move that would push a vertex through the opposite sheet is refused; the others are made.
// Two parallel 4x4 sheets, 0.1 apart: vertex 12 is the lower one's centre.
Mesh TwoSheets() {
  Mesh mesh = MakeFlatSquare(0, 1, 4);
  const Mesh upper = MakeFlatSquare(0.1, 1, 4);
  const int32_t offset = static_cast<int32_t>(mesh.vertices.size());
  for (const auto& v : upper.vertices) mesh.vertices.push_back(v);
  for (const auto& f : upper.faces)
    mesh.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  return mesh;
}

TEST(MeshMoves, AMoveThroughAnotherFaceIsRefused) {
  Mesh mesh = TwoSheets();
  std::vector<Eigen::Vector3d> move(mesh.vertices.size(), Eigen::Vector3d::Zero());
  move[12] = {0, 0, 0.3};  // centre of the lower sheet, through the upper one
  move[0] = {0, 0, 0.02};  // a free move far from it
  MoveOptions options;
  options.tolerance = 1e-6;
  const Eigen::Vector3d centre = mesh.vertices[12];
  const MoveStats stats = MoveVerticesSafely(&mesh, move, options);
  EXPECT_EQ(stats.refused + stats.halved, 1);
  EXPECT_LT(mesh.vertices[12].z(), 0.1);  // halved to below the sheet, or not moved
  EXPECT_EQ(mesh.vertices[0].z(), 0.02);
  EXPECT_EQ(mesh.vertices[12].x(), centre.x());
  EXPECT_TRUE(ValidWithBoundary(mesh));
}

// Without halvings, the move through the upper sheet is refused, and the refused vertices (what
// --refine.unfold moves towards its neighbours next) are that vertex alone.
TEST(MeshMoves, RefusedVerticesAreReported) {
  Mesh mesh = TwoSheets();
  std::vector<Eigen::Vector3d> move(mesh.vertices.size(), Eigen::Vector3d::Zero());
  move[12] = {0, 0, 0.3};
  move[0] = {0, 0, 0.02};
  MoveOptions options;
  options.tolerance = 1e-6;
  options.max_halvings = 0;
  std::vector<uint8_t> refused;
  const MoveStats stats = MoveVerticesSafely(&mesh, move, options, &refused);
  ASSERT_EQ(refused.size(), mesh.vertices.size());
  EXPECT_EQ(stats.refused, 1);
  EXPECT_EQ(refused[12], 1);
  EXPECT_EQ(std::count(refused.begin(), refused.end(), 1), 1);
  EXPECT_EQ(mesh.vertices[0].z(), 0.02);
}

// A fold the checks refuse to close is opened by unfolding, and then the same move is made:
// vertex 12, the centre of a flat 4 x 4 sheet (cells 0.5 wide), leans over towards its neighbour
// 13 at (0.5, 0). Pushed past it, its faces would turn over (refused); moved half way to its
// neighbours' mean (the origin), the push that was refused fits.
TEST(MeshMoves, UnfoldingOpensAFoldTheChecksRefuse) {
  Mesh mesh = MakeFlatSquare(0, 1, 4);
  ASSERT_EQ(mesh.vertices[13], Eigen::Vector3d(0.5, 0, 0));
  mesh.vertices[12] = {0.4, 0, 0.03};
  ASSERT_TRUE(ValidWithBoundary(mesh));
  MoveOptions options;
  options.tolerance = 1e-6;
  options.max_halvings = 0;
  std::vector<Eigen::Vector3d> push(mesh.vertices.size(), Eigen::Vector3d::Zero());
  push[12] = {0.2, 0, 0};
  std::vector<uint8_t> stuck;
  EXPECT_EQ(MoveVerticesSafely(&mesh, push, options, &stuck).refused, 1);
  ASSERT_EQ(stuck[12], 1);
  EXPECT_EQ(mesh.vertices[12], Eigen::Vector3d(0.4, 0, 0.03));

  const std::vector<Eigen::Vector3d> unfold =
      UnfoldingMoves(mesh, VertexNeighbours(mesh), stuck, 0.5);
  EXPECT_TRUE(unfold[12].isApprox(Eigen::Vector3d(-0.2, 0, -0.015), 1e-12)) << unfold[12];
  EXPECT_EQ(unfold[13], Eigen::Vector3d::Zero());  // not stuck: stays
  EXPECT_EQ(MoveVerticesSafely(&mesh, unfold, options, &stuck).moved, 1);
  EXPECT_EQ(MoveVerticesSafely(&mesh, push, options, &stuck).moved, 1);
  EXPECT_TRUE(mesh.vertices[12].isApprox(Eigen::Vector3d(0.4, 0, 0.015), 1e-12))
      << mesh.vertices[12];
  EXPECT_EQ(std::count(stuck.begin(), stuck.end(), 1), 0);
  EXPECT_TRUE(ValidWithBoundary(mesh));
}

// The pyramid scene with its apex pulled down to two thirds of its height: refinement from the
// images alone (no smoothing) brings it back, and the mesh stays free of self-intersections.
TEST(RefineMesh, PullsAFlattenedApexBackToTheTruth) {
  PyramidSceneOptions scene_options;
  scene_options.width = 320;
  scene_options.height = 240;
  const PyramidScene scene = MakePyramidScene(scene_options);
  Mesh mesh = scene.truth;
  ASSERT_DOUBLE_EQ(mesh.vertices[0].z(), scene.pyramid_height);
  mesh.vertices[0].z() = scene.pyramid_height * 2 / 3;
  RefineOptions options;
  options.iterations = 60;
  options.levels = 2;
  options.smoothness = 0;
  options.max_edge_px = 0;  // the apex is vertex 0 throughout: no remeshing
  const RefineStats stats = RefineMesh(&mesh, scene.cameras, kPyramidPairs, options);
  ASSERT_EQ(stats.iterations.size(), 60u);
  EXPECT_LT(stats.iterations.back().energy, 0.5 * stats.iterations.front().energy);
  EXPECT_NEAR(mesh.vertices[0].z(), scene.pyramid_height, 0.01);
  EXPECT_NEAR(mesh.vertices[0].x(), 0, 0.01);
  EXPECT_NEAR(mesh.vertices[0].y(), 0, 0.01);
  EXPECT_TRUE(ValidWithBoundary(mesh));
}

// The lowered pyramid and, behind the cameras (they look down), a small uneven icosahedron no
// camera sees; `seen` gets the pyramid's vertex count (the icosahedron's come after).
Mesh PyramidAndUnseenIcosahedron(const PyramidScene& scene, size_t* seen) {
  Mesh mesh = LoweredApex(scene, 0.8);
  *seen = mesh.vertices.size();
  Eigen::Vector3d behind = Eigen::Vector3d::Zero();
  for (const SweepCamera& camera : scene.cameras) behind += camera.view.Center();
  behind /= static_cast<double>(scene.cameras.size());
  behind.z() += 2 * scene.pyramid_height;
  Mesh unseen = test_meshes::Icosahedron();
  for (size_t v = 0; v < unseen.vertices.size(); ++v) {
    // Uneven, so that its thin-plate gradient is not zero.
    unseen.vertices[v] = behind + 0.1 * (1.0 + 0.05 * static_cast<double>(v)) * unseen.vertices[v];
  }
  const auto offset = static_cast<int32_t>(*seen);
  for (const Eigen::Vector3d& x : unseen.vertices) mesh.vertices.push_back(x);
  for (const auto& f : unseen.faces) {
    mesh.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  }
  return mesh;
}

// What no camera sees stays where it is: a second surface behind the cameras, which the thin
// plate alone would shrink, keeps every vertex bit for bit while the seen pyramid moves.
TEST(RefineMesh, ThinPlateLeavesUnseenVerticesInPlace) {
  const PyramidScene scene = MakePyramidScene();
  size_t seen = 0;
  Mesh mesh = PyramidAndUnseenIcosahedron(scene, &seen);
  const Mesh start = mesh;
  RefineOptions options;
  options.iterations = 4;
  options.levels = 1;
  options.smoothness = 0.03;
  options.max_edge_px = 0;  // vertex for vertex: no remeshing
  RefineMesh(&mesh, scene.cameras, kPyramidPairs, options);
  EXPECT_NE(mesh.vertices[0], start.vertices[0]);
  for (size_t v = seen; v < mesh.vertices.size(); ++v) {
    EXPECT_EQ(mesh.vertices[v], start.vertices[v]) << "unseen vertex " << v;
  }
  EXPECT_TRUE(ValidWithBoundary(mesh));
}

// Remeshing leaves what no camera sees alone too: no edge there is split (none is too long for
// an image) or collapsed (none is too short for one), so the icosahedron behind the cameras
// keeps its 12 vertices and 20 faces, while the seen pyramid is remeshed.
TEST(RefineMesh, RemeshingLeavesUnseenFacesAlone) {
  const PyramidScene scene = MakePyramidScene();
  size_t seen = 0;
  Mesh mesh = PyramidAndUnseenIcosahedron(scene, &seen);
  const std::vector<Eigen::Vector3d> unseen(mesh.vertices.begin() + static_cast<long>(seen),
                                            mesh.vertices.end());
  RefineOptions options;
  options.iterations = 1;
  options.levels = 1;
  options.max_edge_px = 100;
  options.min_edge_px = 40;  // collapse boldly wherever an image measures an edge
  const RefineStats stats = RefineMesh(&mesh, scene.cameras, kPyramidPairs, options);
  EXPECT_GT(stats.splits + stats.collapses, 0);
  std::vector<uint8_t> is_unseen(mesh.vertices.size(), 0);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    is_unseen[v] = std::find(unseen.begin(), unseen.end(), mesh.vertices[v]) != unseen.end();
  }
  EXPECT_EQ(std::count(is_unseen.begin(), is_unseen.end(), 1), 12);
  EXPECT_EQ(std::count_if(mesh.faces.begin(), mesh.faces.end(),
                          [&](const auto& f) {
                            return is_unseen[f[0]] && is_unseen[f[1]] && is_unseen[f[2]];
                          }),
            20);
  EXPECT_TRUE(ValidWithBoundary(mesh));
}

// The faces of `mesh` that pass within `radius` of x, as their corners' positions.
std::vector<std::array<Eigen::Vector3d, 3>> FacesNear(const Mesh& mesh, const Eigen::Vector3d& x,
                                                      double radius) {
  std::vector<std::array<Eigen::Vector3d, 3>> near;
  for (const auto& f : mesh.faces) {
    const std::array<Eigen::Vector3d, 3> t = {mesh.vertices[f[0]], mesh.vertices[f[1]],
                                              mesh.vertices[f[2]]};
    if ((x - ClosestPointOnTriangle(x, t)).norm() < radius) near.push_back(t);
  }
  return near;
}

// A camera whose centre is already nearer the surface than the moves' clearance (a swept mesh
// can pass that near one) does not stop the level's remeshing: the faces near it stay as they
// are, and the rest is remeshed. Splitting them would bring the surface nearer still (a split
// point lies off its edge), and the pixel footprint, shrinking towards the camera, would ask for
// splits without end. Gradients are zero, so that only the remeshing changes the mesh.
TEST(RefineMesh, RemeshingLeavesFacesNearACameraAlone) {
  const PyramidScene scene = MakePyramidScene();
  Mesh mesh = LoweredApex(scene, 0.8);
  SplitLongEdges(
      &mesh, [](const Eigen::Vector3d& x) { return x.norm() < 3 ? 0.3 : 1e9; }, 100000, 1e-9);
  // A fourth camera 3 mm off a face of the pyramid's +x side, looking along the surface.
  const auto on_side = std::min_element(mesh.faces.begin(), mesh.faces.end(), [&](auto f, auto g) {
    const auto middle = [&](const auto& t) {
      return (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3;
    };
    const Eigen::Vector3d target(0.5, 0, 0.12);
    return (middle(f) - target).norm() < (middle(g) - target).norm();
  });
  const Eigen::Vector3d normal = FaceCross(mesh.vertices, *on_side).normalized();
  ASSERT_GT(normal.z(), 0);
  const Eigen::Vector3d middle =
      (mesh.vertices[(*on_side)[0]] + mesh.vertices[(*on_side)[1]] + mesh.vertices[(*on_side)[2]]) /
      3;
  const Eigen::Vector3d tangent = normal.cross(Eigen::Vector3d::UnitY()).normalized();
  std::vector<SweepCamera> cameras = scene.cameras;
  SweepCamera near_camera = cameras[0];
  near_camera.id = 3;
  near_camera.view =
      LookAtView(middle + 0.003 * normal, middle + tangent + 0.2 * normal, 160, 120, 150);
  cameras.push_back(near_camera);
  const Eigen::Vector3d centre = near_camera.view.Center();
  const std::vector<std::array<Eigen::Vector3d, 3>> near_before = FacesNear(mesh, centre, 0.01);
  ASSERT_FALSE(near_before.empty());
  const size_t vertices_before = mesh.vertices.size();

  RefineOptions options;
  options.iterations = 1;
  options.levels = 1;
  options.max_vertices = 20000;
  RefineHooks hooks;
  hooks.pair_gradients = [](const Mesh& at, int, std::vector<PairGradient>* per_pair) {
    for (PairGradient& g : *per_pair) {
      g.Resize(at.vertices.size());
      g.pixels = 1;  // a defined pixel, of energy 0
    }
    return true;
  };
  const RefineStats stats = RefineMesh(&mesh, cameras, kPyramidPairs, options, hooks);
  EXPECT_EQ(stats.remeshings_undone, 0);
  EXPECT_GT(stats.splits, 0);
  EXPECT_GT(mesh.vertices.size(), vertices_before);
  const std::vector<std::array<Eigen::Vector3d, 3>> near_after = FacesNear(mesh, centre, 0.01);
  ASSERT_EQ(near_after.size(), near_before.size());
  for (size_t i = 0; i < near_before.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(near_after[i][k], near_before[i][k]);
  }
  EXPECT_TRUE(ValidWithBoundary(mesh));
}

// Pairs are summed in pair order whatever the threads did: one thread and two give the same
// mesh, bit for bit.
TEST(RefineMesh, ThreadsDoNotChangeTheResult) {
  const PyramidScene scene = MakePyramidScene();
  const Mesh start = LoweredApex(scene, 0.8);
  RefineOptions options;
  options.iterations = 4;
  options.levels = 1;
  Mesh one = start, two = start;
  options.threads = 1;
  RefineMesh(&one, scene.cameras, kPyramidPairs, options);
  options.threads = 2;
  RefineMesh(&two, scene.cameras, kPyramidPairs, options);
  ASSERT_NE(one.vertices[0], start.vertices[0]);
  ExpectSameVertices(one, two);
  EXPECT_TRUE(ValidWithBoundary(one));
}

// Splitting keeps a closed 2-manifold closed, valid and in place: every edge ends at most as long
// as asked (the icosahedron's creases included: no split refused), the surface area does not
// change, and Euler's formula still gives genus 0.
TEST(Remesh, SplitLongEdgesKeepsAClosedValidMeshInPlace) {
  Mesh mesh = test_meshes::Icosahedron();
  const double area = mesh.SurfaceArea();
  const double limit = 0.3;
  // The refiner's tolerance: twice check-mesh's.
  const double tolerance =
      2 * FloatCheckTolerance(mesh, std::vector<uint8_t>(mesh.faces.size(), 1));
  const SplitStats stats = SplitLongEdges(
      &mesh, [&](const Eigen::Vector3d&) { return limit; }, 1000000, tolerance);
  EXPECT_EQ(stats.refused, 0);
  EXPECT_GT(stats.splits, 100);
  EXPECT_EQ(mesh.NumVertices(), 12 + static_cast<size_t>(stats.splits));
  EXPECT_EQ(mesh.NumFaces(), 20 + 2 * static_cast<size_t>(stats.splits));
  EXPECT_NEAR(mesh.SurfaceArea(), area, 1e-3 * area);  // split points are 8 tolerances off
  for (const auto& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE((mesh.vertices[f[k]] - mesh.vertices[f[(k + 1) % 3]]).norm(), limit);
    }
  }
  const MeshReport report = CheckMesh(mesh);
  EXPECT_TRUE(report.is_valid);
  ASSERT_TRUE(report.genus.has_value());
  EXPECT_EQ(*report.genus, 0);
}

// Faces with an angle below `degrees`.
int64_t ThinFaces(const Mesh& mesh, double degrees) {
  int64_t thin = 0;
  for (const auto& f : mesh.faces) {
    double smallest = M_PI;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d u = mesh.vertices[f[(k + 1) % 3]] - mesh.vertices[f[k]];
      const Eigen::Vector3d v = mesh.vertices[f[(k + 2) % 3]] - mesh.vertices[f[k]];
      smallest = std::min(smallest, std::atan2(u.cross(v).norm(), u.dot(v)));
    }
    thin += smallest < degrees * M_PI / 180;
  }
  return thin;
}

// Flips after splitting round the faces inside the icosahedron's flat faces and never across
// its creases (41.8 degrees): same faces count, same area, a valid closed genus-0 mesh, and
// fewer thin faces (the slivers left along the creases by splitting stay: flipping them would
// fold the surface).
TEST(Remesh, FlipsRoundFlatFacesAndKeepAClosedValidMesh) {
  Mesh mesh = test_meshes::Icosahedron();
  const double tolerance =
      2 * FloatCheckTolerance(mesh, std::vector<uint8_t>(mesh.faces.size(), 1));
  SplitLongEdges(
      &mesh, [](const Eigen::Vector3d& x) { return x.x() > 0 ? 0.2 : 0.45; }, 1000000, tolerance);
  const Mesh split = mesh;
  const FlipStats stats = FlipEdges(&mesh, 10, tolerance);
  EXPECT_GT(stats.flips, 20);
  EXPECT_EQ(mesh.NumFaces(), split.NumFaces());
  EXPECT_NEAR(mesh.SurfaceArea(), split.SurfaceArea(), 1e-3 * split.SurfaceArea());
  EXPECT_LT(ThinFaces(mesh, 20), ThinFaces(split, 20));
  const MeshReport report = CheckMesh(mesh);
  EXPECT_TRUE(report.is_valid) << report.ToTable();
  ASSERT_TRUE(report.genus.has_value());
  EXPECT_EQ(*report.genus, 0);
  // No face pair across a crease flipped: every vertex stays on the icosahedron's surface,
  // and flipping again finds nothing left to do.
  EXPECT_EQ(FlipEdges(&mesh, 10, tolerance).flips, 0);
}

// Collapsing edges shorter than a limit keeps a closed 2-manifold closed, valid, genus 0 and in
// place (area within 2%): each collapse removes one vertex and two faces.
TEST(Remesh, CollapsesKeepAClosedValidMeshInPlace) {
  Mesh mesh = test_meshes::Icosahedron();
  const double tolerance =
      2 * FloatCheckTolerance(mesh, std::vector<uint8_t>(mesh.faces.size(), 1));
  SplitLongEdges(
      &mesh, [](const Eigen::Vector3d&) { return 0.15; }, 1000000, tolerance);
  const Mesh split = mesh;
  // Collapse where x > 0 only: the other half keeps its short edges.
  const CollapseStats stats = CollapseShortEdges(
      &mesh, [](const Eigen::Vector3d& x) { return x.x() > 0 ? 0.12 : 0.0; }, 60, tolerance);
  EXPECT_GT(stats.collapses, 30);
  EXPECT_EQ(mesh.NumVertices() + static_cast<size_t>(stats.collapses), split.NumVertices());
  EXPECT_EQ(mesh.NumFaces() + 2 * static_cast<size_t>(stats.collapses), split.NumFaces());
  EXPECT_NEAR(mesh.SurfaceArea(), split.SurfaceArea(), 0.02 * split.SurfaceArea());
  const MeshReport report = CheckMesh(mesh);
  EXPECT_TRUE(report.is_valid) << report.ToTable();
  ASSERT_TRUE(report.genus.has_value());
  EXPECT_EQ(*report.genus, 0);
}

// The vertex budget stops splitting.
TEST(Remesh, SplittingStopsAtTheVertexBudget) {
  Mesh mesh = test_meshes::Icosahedron();
  SplitLongEdges(
      &mesh, [](const Eigen::Vector3d&) { return 0.01; }, 50, 1e-9);
  EXPECT_EQ(mesh.NumVertices(), 50u);
  EXPECT_TRUE(CheckMesh(mesh).is_valid);
}

// A refinement resumed from a checkpoint ends with the mesh of an uninterrupted one, bit for bit,
// remeshing, backtracking and unfolding included (the checkpoint is taken inside the second
// level, with refused vertices waiting to unfold).
TEST(RefineMesh, ResumingFromACheckpointGivesTheSameMesh) {
  const PyramidScene scene = MakePyramidScene();
  const Mesh start = LoweredApex(scene, 0.7);
  RefineOptions options;
  options.iterations = 8;
  options.levels = 2;
  options.max_edge_px = 40;
  options.max_face_turn_deg = 1;  // so that some moves are refused and unfold at the next step
  options.max_halvings = 0;
  Mesh whole = start;
  Mesh saved_mesh;
  RefineState saved;
  RefineHooks hooks;
  hooks.checkpoint = [&](const Mesh& mesh, const RefineState& state) {
    if (state.iterations_done == 6) {
      saved_mesh = mesh;
      saved = state;
    }
  };
  const RefineStats stats = RefineMesh(&whole, scene.cameras, kPyramidPairs, options, hooks);
  ASSERT_GT(stats.splits, 0);
  ASSERT_EQ(saved.level_index, 1);
  ASSERT_EQ(saved.iteration_in_level, 2);
  ASSERT_FALSE(saved.stuck.empty()) << "no refused vertex at the checkpoint: unfolding untested";
  Mesh resumed = saved_mesh;
  RefineHooks resume;
  resume.resume = &saved;
  const RefineStats rest = RefineMesh(&resumed, scene.cameras, kPyramidPairs, options, resume);
  ASSERT_EQ(rest.iterations.size(), 2u);
  EXPECT_EQ(rest.iterations.front().iteration, 7);
  ASSERT_EQ(resumed.faces, whole.faces);
  ExpectSameVertices(resumed, whole);
  EXPECT_TRUE(ValidWithBoundary(whole));
}

// A mesh no camera sees (another scene's, or misplaced) is an input error, not a silent no-op.
TEST(RefineMesh, AMeshNoCameraSeesIsAnInputError) {
  const PyramidScene scene = MakePyramidScene();
  Mesh elsewhere = scene.truth;
  for (Eigen::Vector3d& v : elsewhere.vertices) v.x() += 1000;
  RefineOptions options;
  options.iterations = 2;
  options.levels = 1;
  EXPECT_THROW(RefineMesh(&elsewhere, scene.cameras, {{0, 1}, {1, 0}}, options), InputError);
}

// A pair's gradient survives the wire bit for bit (only touched vertices travel), and a
// message that does not fit the job's mesh is refused with a reason, never summed.
TEST(RefineWire, RoundTripsBitForBitAndRefusesWhatDoesNotFit) {
  const RefineView a = NoiseView(LookAtView({0.03, -0.02, 3}, {0.01, 0.02, 0}, 160, 120, 150), 1);
  const RefineView b = NoiseView(LookAtView({0.6, 0.1, 2.9}, {0, 0, 0}, 160, 120, 150), 2);
  Mesh mesh = BumpyGrid();
  mesh.vertices.emplace_back(50, 50, 50);  // seen by nobody: stays off the wire
  const PairGradient g = ComputePairGradientFast(mesh, a, b, RefineOptions());
  wire::PairGradient packed;
  PairGradientToWire(g, &packed);
  EXPECT_LT(packed.vertices().size() / 4, mesh.vertices.size());
  std::string problem;
  const PairGradient back = PairGradientFromWire(packed, mesh.vertices.size(), &problem);
  ASSERT_EQ(problem, "");
  EXPECT_EQ(back.energy, g.energy);
  EXPECT_EQ(back.pixels, g.pixels);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    EXPECT_EQ(back.gradient[v], g.gradient[v]);
    EXPECT_EQ(back.parallax_rate2[v], g.parallax_rate2[v]);
    EXPECT_EQ(back.weight[v], g.weight[v]);
  }
  const auto refused = [&](wire::PairGradient bad, size_t vertices) {
    std::string why;
    PairGradientFromWire(bad, vertices, &why);
    return !why.empty();
  };
  EXPECT_TRUE(refused(packed, mesh.vertices.size() + 1));  // another mesh
  wire::PairGradient bad = packed;
  bad.set_energy(std::nan(""));
  EXPECT_TRUE(refused(bad, mesh.vertices.size()));
  bad = packed;
  bad.set_energy(3.0 * static_cast<double>(packed.pixels()));  // 1 - ZNCC is at most 2
  EXPECT_TRUE(refused(bad, mesh.vertices.size()));
  bad = packed;
  bad.mutable_values()->pop_back();  // sizes disagree
  EXPECT_TRUE(refused(bad, mesh.vertices.size()));
  bad = packed;
  std::swap((*bad.mutable_vertices())[0], (*bad.mutable_vertices())[4]);  // not ascending
  EXPECT_TRUE(refused(bad, mesh.vertices.size()));
  bad = packed;
  const double nan = std::nan(""), negative = -1;
  bad.mutable_values()->replace(0, 8, reinterpret_cast<const char*>(&nan), 8);
  EXPECT_TRUE(refused(bad, mesh.vertices.size()));
  bad = packed;
  bad.mutable_values()->replace(32, 8, reinterpret_cast<const char*>(&negative), 8);  // weight
  EXPECT_TRUE(refused(bad, mesh.vertices.size()));
}

}  // namespace
}  // namespace ms
