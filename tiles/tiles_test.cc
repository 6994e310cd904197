#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <set>

#include "base/error.h"
#include "manifold/cell_ray_counts.h"
#include "manifold/tile_manifold.h"
#include "mesh/mesh.h"
#include "mesh/mesh_checker.h"
#include "tiles/tile_growth.h"
#include "tiles/tile_layout.h"
#include "tiles/tile_stars.h"

namespace ms {
namespace {

std::vector<Eigen::Vector3d> RandomPoints(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) points.emplace_back(u(rng), u(rng), u(rng));
  return points;
}

// Appends the corners of [lo, hi]^3 and returns their ids: the hull every tile holds.
std::vector<int32_t> AddHullCorners(double lo, double hi, std::vector<Eigen::Vector3d>* points) {
  std::vector<int32_t> ids;
  for (int c = 0; c < 8; ++c) {
    ids.push_back(static_cast<int32_t>(points->size()));
    points->emplace_back(c & 1 ? hi : lo, c & 2 ? hi : lo, c & 4 ? hi : lo);
  }
  return ids;
}

// The whole triangulation's finite cells, as one tile owning everything holds them.
std::vector<TileCell> WholeCells(const std::vector<Eigen::Vector3d>& points) {
  TileHolding all;
  for (int32_t i = 0; i < static_cast<int32_t>(points.size()); ++i) all.owned.push_back(i);
  return OwnedCells(points, all);
}

// The tiles' owned cells, each cell once, must be exactly the whole triangulation's.
void ExpectTilesPartitionTheWhole(const std::vector<Eigen::Vector3d>& points,
                                  const std::vector<int32_t>& hull, int tiles) {
  SCOPED_TRACE("tiles " + std::to_string(tiles));
  const TileLayout layout = TileLayout::Split(points, tiles);
  StarExchangeStats stats;
  const std::vector<TileHolding> holdings = ExchangeStarPoints(points, hull, layout, &stats);
  ASSERT_EQ(static_cast<int>(holdings.size()), tiles);
  std::vector<TileCell> united;
  size_t owned_points = 0;
  for (const TileHolding& h : holdings) {
    owned_points += h.owned.size();
    const std::vector<TileCell> cells = OwnedCells(points, h);
    united.insert(united.end(), cells.begin(), cells.end());
  }
  EXPECT_EQ(owned_points, points.size());
  std::sort(united.begin(), united.end());
  EXPECT_EQ(std::adjacent_find(united.begin(), united.end()), united.end())
      << "a cell owned by two tiles";
  const std::vector<TileCell> whole = WholeCells(points);
  EXPECT_EQ(united.size(), whole.size());
  EXPECT_TRUE(united == whole) << "the tiles' cells differ from the whole triangulation's";
  // Tiles of one colour share no star.
  const std::vector<std::vector<int>> neighbours = TileNeighbours(points, holdings, layout);
  const std::vector<int> colour = ColourTiles(neighbours);
  for (int t = 0; t < tiles; ++t) {
    for (int other : neighbours[t]) {
      EXPECT_NE(colour[t], colour[other]) << t << " and " << other;
      EXPECT_TRUE(std::binary_search(neighbours[other].begin(), neighbours[other].end(), t));
    }
  }
  for (int t = 0; t < tiles; ++t) {
    // The stars growing reads: every cell there is a cell of the whole, so each star is whole,
    // and its owner is a neighbour.
    const std::vector<TileCell> around = CellsAroundOwnedCells(points, holdings[t]);
    EXPECT_TRUE(std::includes(whole.begin(), whole.end(), around.begin(), around.end()))
        << "a star around a tile's cells differs from the whole triangulation's";
    for (const TileCell& cell : around) {
      const int owner = layout.TileOf(points[cell[0]]);
      if (owner != t) {
        EXPECT_TRUE(std::binary_search(neighbours[t].begin(), neighbours[t].end(), owner));
      }
    }
  }
  if (tiles > 1) {
    EXPECT_GT(stats.foreign_points, 0);
    EXPECT_GE(stats.rounds, 2);
  }
}

TEST(TileLayout, SplitsBalanceThePointsAndCoverSpace) {
  const std::vector<Eigen::Vector3d> points = RandomPoints(1000, 1);
  for (int tiles : {1, 2, 3, 5, 8}) {
    const TileLayout layout = TileLayout::Split(points, tiles);
    std::vector<int> counts(tiles, 0);
    for (const auto& p : points) ++counts[layout.TileOf(p)];
    const auto [least, most] = std::minmax_element(counts.begin(), counts.end());
    // Shares of floor/ceil(n / tiles) up to one point lost per split level.
    EXPECT_LE(*most - *least, 1000 / tiles / 10 + 3) << tiles << " tiles";
    for (const auto& p : points) {
      const int t = layout.TileOf(p);
      EXPECT_TRUE((p.array() >= layout.lower(t).array()).all() &&
                  (p.array() < layout.upper(t).array()).all());
    }
    // Far points still have a tile.
    EXPECT_GE(layout.TileOf(Eigen::Vector3d(1e30, -1e30, 5)), 0);
  }
}

TEST(TileLayout, TilesMeetingABoxAreThoseWhoseRegionsMeetIt) {
  const TileLayout layout = TileLayout::Split(RandomPoints(500, 2), 6);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    const Eigen::Vector3d lo = a.cwiseMin(b), hi = a.cwiseMax(b);
    std::vector<int> expected;
    for (int t = 0; t < layout.num_tiles(); ++t) {
      if ((lo.array() < layout.upper(t).array()).all() &&
          (hi.array() >= layout.lower(t).array()).all()) {
        expected.push_back(t);
      }
    }
    EXPECT_EQ(layout.TilesMeeting(lo, hi), expected);
  }
}

TEST(TileLayout, JsonRoundTripKeepsEveryTile) {
  const std::vector<Eigen::Vector3d> points = RandomPoints(300, 4);
  const TileLayout layout = TileLayout::Split(points, 5);
  const TileLayout read = TileLayout::FromJson(layout.ToJson(), "tiles.json");
  EXPECT_EQ(read.num_tiles(), 5);
  for (const auto& p : points) EXPECT_EQ(read.TileOf(p), layout.TileOf(p));
  EXPECT_EQ(read.ToJson(), layout.ToJson());
}

TEST(TileLayout, BadInputNamesItsSource) {
  EXPECT_THROW(TileLayout::Split(RandomPoints(10, 5), 0), InputError);
  std::vector<Eigen::Vector3d> nan_point = RandomPoints(10, 5);
  nan_point[3].y() = std::nan("");
  EXPECT_THROW(TileLayout::Split(nan_point, 2), InputError);
  for (const char* json :
       {"{", "{\"tiles\": 2}", "{\"tiles\": 2, \"nodes\": [{\"tile\": 0}]}",
        "{\"tiles\": 2, \"nodes\": [{\"axis\": 0, \"split\": 0.5, \"low\": 0, \"high\": 2}, "
        "{\"tile\": 0}, {\"tile\": 1}]}",
        "{\"tiles\": 2, \"nodes\": [{\"axis\": 0, \"split\": 0.5, \"low\": 1, \"high\": 2}, "
        "{\"tile\": 1}, {\"tile\": 1}]}"}) {
    try {
      TileLayout::FromJson(json, "run/tiles.json");
      ADD_FAILURE() << "accepted " << json;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("run/tiles.json"), std::string::npos) << e.what();
    }
  }
}

TEST(TileStars, TilesPartitionTheTriangulationOfRandomPoints) {
  std::vector<Eigen::Vector3d> points = RandomPoints(3000, 6);
  const std::vector<int32_t> hull = AddHullCorners(-1, 2, &points);
  for (int tiles : {1, 2, 3, 5, 8}) ExpectTilesPartitionTheWhole(points, hull, tiles);
}

// A grid: every cube's eight corners lie on one sphere, so the triangulation is decided by
// CGAL's symbolic perturbation, which each tile must reproduce.
TEST(TileStars, TilesPartitionTheTriangulationOfCosphericalGridPoints) {
  std::vector<Eigen::Vector3d> points;
  for (int x = 0; x < 9; ++x) {
    for (int y = 0; y < 9; ++y) {
      for (int z = 0; z < 9; ++z) points.emplace_back(x, y, z);
    }
  }
  const std::vector<int32_t> hull = AddHullCorners(-3, 11, &points);
  for (int tiles : {2, 4, 7}) ExpectTilesPartitionTheWhole(points, hull, tiles);
}

// Facades: points on a few planes with little noise make long flat cells whose circumspheres
// reach far across seams.
TEST(TileStars, TilesPartitionTheTriangulationOfPlanarFacades) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1), noise(-1e-3, 1e-3);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 2500; ++i) {
    const int facade = i % 4;
    const double a = 20 * u(rng), h = 8 * u(rng);
    points.emplace_back(facade < 2 ? a : facade * 3.0 + noise(rng),
                        facade < 2 ? facade * 6.0 + noise(rng) : a, h);
  }
  const std::vector<int32_t> hull = AddHullCorners(-10, 30, &points);
  for (int tiles : {2, 4, 8}) ExpectTilesPartitionTheWhole(points, hull, tiles);
}

// What the exchange is for: tiles that hold only their own points and the hull get cells wrong
// along the seams.
TEST(TileStars, WithoutTheExchangeTheSeamsDiffer) {
  std::vector<Eigen::Vector3d> points = RandomPoints(1000, 10);
  const std::vector<int32_t> hull = AddHullCorners(-1, 2, &points);
  const TileLayout layout = TileLayout::Split(points, 4);
  std::vector<TileCell> united;
  for (TileHolding h : ExchangeStarPoints(points, hull, layout)) {
    std::vector<int32_t> kept;
    for (int32_t id : h.foreign) {
      if (std::find(hull.begin(), hull.end(), id) != hull.end()) kept.push_back(id);
    }
    h.foreign = kept;
    const std::vector<TileCell> cells = OwnedCells(points, h);
    united.insert(united.end(), cells.begin(), cells.end());
  }
  std::sort(united.begin(), united.end());
  EXPECT_FALSE(united == WholeCells(points));
}

// Cameras among the points, and rays from three of them to every point but the hull's.
struct RayScene {
  std::vector<Eigen::Vector3d> cameras;
  std::vector<ViewingRay> rays;
};
RayScene CamerasAndRays(const std::vector<Eigen::Vector3d>& points,
                        const std::vector<int32_t>& hull, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  RayScene scene;
  for (int c = 0; c < 8; ++c) scene.cameras.emplace_back(u(rng), u(rng), u(rng));
  for (int32_t id = 0; id < static_cast<int32_t>(points.size()); ++id) {
    if (std::find(hull.begin(), hull.end(), id) != hull.end()) continue;
    for (int k = 0; k < 3; ++k) scene.rays.push_back({static_cast<int32_t>(rng() % 8), id});
  }
  return scene;
}

// The rays a tile counts on the cells it owns (TileManifold walks them through its own
// triangulation; most end at points it does not hold).
std::vector<CellRayCount> OwnedCounts(const std::vector<Eigen::Vector3d>& points,
                                      const std::vector<int32_t>& held,
                                      const std::function<bool(int32_t)>& owns,
                                      const RayScene& scene) {
  const int32_t no_steiner = static_cast<int32_t>(points.size());
  return TileManifold(points, held, owns, no_steiner, false, scene.cameras, scene.rays,
                      ManifoldOptions())
      .OwnedCounts();
}

// Together the tiles' counts on their cells, each cell once.
std::vector<CellRayCount> UnitedTileCounts(const std::vector<Eigen::Vector3d>& points,
                                           const std::vector<TileHolding>& holdings,
                                           const RayScene& scene) {
  std::vector<int> owner(points.size(), -1);
  for (size_t t = 0; t < holdings.size(); ++t) {
    for (int32_t id : holdings[t].owned) owner[id] = static_cast<int>(t);
  }
  std::vector<CellRayCount> united;
  for (size_t t = 0; t < holdings.size(); ++t) {
    std::vector<int32_t> held = holdings[t].owned;
    held.insert(held.end(), holdings[t].foreign.begin(), holdings[t].foreign.end());
    const std::vector<CellRayCount> counts = OwnedCounts(
        points, held, [&](int32_t id) { return owner[id] == static_cast<int>(t); }, scene);
    united.insert(united.end(), counts.begin(), counts.end());
  }
  std::sort(united.begin(), united.end(),
            [](const CellRayCount& a, const CellRayCount& b) { return a.ids < b.ids; });
  return united;
}

// Random points in a hull of corners, cameras and rays, and the whole triangulation's counts.
struct RayCase {
  std::vector<Eigen::Vector3d> points;
  std::vector<int32_t> hull;
  RayScene scene;
  std::vector<CellRayCount> whole;
};
RayCase MakeRayCase() {
  RayCase c;
  c.points = RandomPoints(800, 5);
  c.hull = AddHullCorners(-1, 2, &c.points);
  c.scene = CamerasAndRays(c.points, c.hull, 9);
  std::vector<int32_t> all(c.points.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int32_t>(i);
  c.whole = OwnedCounts(
      c.points, all, [](int32_t) { return true; }, c.scene);
  return c;
}

TEST(TileRays, TilesCountTheWholeTriangulationsRaysOnTheirCells) {
  const RayCase c = MakeRayCase();
  int64_t whole_crossings = 0;
  for (const CellRayCount& n : c.whole) whole_crossings += n.crossings;
  ASSERT_GT(whole_crossings, static_cast<int64_t>(c.scene.rays.size()));
  for (int tiles : {2, 5}) {
    SCOPED_TRACE("tiles " + std::to_string(tiles));
    const TileLayout layout = TileLayout::Split(c.points, tiles);
    const std::vector<CellRayCount> united =
        UnitedTileCounts(c.points, ExchangeStarPoints(c.points, c.hull, layout), c.scene);
    ASSERT_EQ(united.size(), c.whole.size());
    EXPECT_TRUE(united == c.whole) << "a tile's counts differ from the whole triangulation's";
  }
}

// Without the exchange a tile's cells near its seams are not the whole's, nor their counts.
TEST(TileRays, WithoutTheExchangeTheCountsDiffer) {
  const RayCase c = MakeRayCase();
  const std::vector<Eigen::Vector3d>& points = c.points;
  const std::vector<int32_t>& hull = c.hull;
  const TileLayout layout = TileLayout::Split(points, 4);
  std::vector<TileHolding> bare = ExchangeStarPoints(points, hull, layout);
  for (TileHolding& h : bare) {
    h.foreign.clear();
    for (int32_t id : hull) {
      if (!std::binary_search(h.owned.begin(), h.owned.end(), id)) h.foreign.push_back(id);
    }
  }
  const std::vector<CellRayCount> united = UnitedTileCounts(points, bare, c.scene);
  EXPECT_FALSE(united == c.whole);
}

// A sphere of points seen from cameras around it, inside a box of Steiner corners: growing
// fills the seen space around the sphere.
TiledScene SphereScene(int count) {
  TiledScene scene;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1 - 2 * (i + 0.5) / count, r = std::sqrt(1 - z * z);
    scene.points.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  scene.first_steiner = count;
  scene.hull = AddHullCorners(-4, 4, &scene.points);
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  for (int c = 0; c < 14; ++c) {
    scene.cameras.push_back(2.5 * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized());
  }
  for (int32_t id = 0; id < count; ++id) {
    const Eigen::Vector3d& p = scene.points[id];
    for (int32_t c = 0; c < static_cast<int32_t>(scene.cameras.size()); ++c) {
      const Eigen::Vector3d to_camera = scene.cameras[c] - p;
      if (p.dot(to_camera) > 0.3 * to_camera.norm()) scene.rays.push_back({c, id});
    }
  }
  return scene;
}

// The layout of `tiles` tiles over the scene's own points (not its Steiner points).
TileLayout LayoutOfScenePoints(const TiledScene& scene, int tiles) {
  const std::vector<Eigen::Vector3d> scene_points(scene.points.begin(),
                                                  scene.points.begin() + scene.first_steiner);
  return TileLayout::Split(scene_points, tiles);
}

TEST(TileGrowth, TilesGrowOneClosedManifoldStitchedByIds) {
  const TiledScene scene = SphereScene(600);
  int64_t untiled_outside = 0;
  for (int tiles : {1, 2, 4, 8}) {
    SCOPED_TRACE("tiles " + std::to_string(tiles));
    const TiledSurface grown =
        GrowTiles(scene, LayoutOfScenePoints(scene, tiles), ManifoldOptions());
    std::vector<TileManifold::Cell> outside;
    for (const auto& cells : grown.outside)
      outside.insert(outside.end(), cells.begin(), cells.end());
    std::sort(outside.begin(), outside.end());
    ASSERT_GT(outside.size(), 100u);
    EXPECT_EQ(std::adjacent_find(outside.begin(), outside.end()), outside.end())
        << "a cell in two tiles' O";
    // The faces the tiles give, stitched by point id, are one closed 2-manifold (exact: every
    // vertex's faces are one cycle, every edge in two faces, consistently oriented).
    Mesh mesh;
    mesh.vertices = scene.points;
    mesh.faces = grown.faces;
    const MeshReport report = CheckMesh(mesh);
    EXPECT_TRUE(report.is_closed_manifold) << report.ToTable();
    EXPECT_GT(report.num_faces, 600);
    if (tiles == 1) untiled_outside = static_cast<int64_t>(outside.size());
    std::printf("tiles %d: %zu cells in O, %zu faces, %d rounds, %d colours\n", tiles,
                outside.size(), grown.faces.size(), grown.stats.rounds, grown.stats.colours);
    // Another growing order (a queue per tile, in bands of weight), much the same free space.
    EXPECT_NEAR(static_cast<double>(outside.size()), static_cast<double>(untiled_outside),
                0.02 * untiled_outside);
    EXPECT_GT(grown.stats.rounds, 0);
    if (tiles > 1) {
      EXPECT_GT(grown.stats.labels_read, 0);
    }
  }
}

// Tiles of one phase grow on threads; what they flip is read in tile order, so the surface is
// the same with any number of threads.
TEST(TileGrowth, ThreadsDoNotChangeTheSurface) {
  const TiledScene scene = SphereScene(600);
  const TileLayout layout = LayoutOfScenePoints(scene, 8);
  TileGrowthOptions one, four;
  one.threads = 1;
  four.threads = 4;
  const TiledSurface a = GrowTiles(scene, layout, ManifoldOptions(), one);
  const TiledSurface b = GrowTiles(scene, layout, ManifoldOptions(), four);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.outside, b.outside);
  EXPECT_EQ(a.stats.rounds, b.stats.rounds);
  EXPECT_EQ(a.stats.labels_read, b.stats.labels_read);
}

// Tiles weigh their cells by the threshold only: the rules they do not have are refused by
// name, not silently replaced.
TEST(TileGrowth, RefusesFreeSpaceRulesItDoesNotHave) {
  const TiledScene scene = SphereScene(200);
  const TileLayout layout = LayoutOfScenePoints(scene, 2);
  ManifoldOptions cut, behind;
  cut.visibility = FreeSpaceRule::kCut;
  behind.behind_ratio = 1;
  for (const ManifoldOptions& options : {cut, behind}) {
    try {
      GrowTiles(scene, layout, options);
      ADD_FAILURE() << "not refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--manifold.visibility cut"), std::string::npos);
    }
  }
}

TEST(TileStars, RefusesAPointOutsideTheHull) {
  std::vector<Eigen::Vector3d> points = RandomPoints(200, 8);
  const std::vector<int32_t> hull = AddHullCorners(-1, 2, &points);
  points.emplace_back(5, 0.5, 0.5);
  const TileLayout layout = TileLayout::Split(points, 2);
  try {
    ExchangeStarPoints(points, hull, layout);
    ADD_FAILURE() << "accepted a point outside the hull";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 208"), std::string::npos) << e.what();
  }
}

TEST(TileStars, RefusesRepeatedPoints) {
  std::vector<Eigen::Vector3d> points = RandomPoints(200, 9);
  points.push_back(points[17]);
  const std::vector<int32_t> hull = AddHullCorners(-1, 2, &points);
  EXPECT_THROW(ExchangeStarPoints(points, hull, TileLayout::Split(points, 3)), InputError);
}

}  // namespace
}  // namespace ms
