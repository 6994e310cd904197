// What splitting a scene into tiles costs each tile (docs/design/scalability.md, "Tiles"):
//   tiles_bench SCENE [--tiles 1 2 4 8] [--rays] [--grow DIR] [--json FILE]
// The vertices are the scene's points (near-duplicates merged as the manifold merges them) and
// the Steiner points the manifold adds: the box grid (which every tile holds) and the graded
// points in the empty space, all of them (--manifold.graded-steiner on; by default the manifold
// keeps those hidden in every view or in open air). For each tile
// count: the k-d layout, the exchange that makes every tile's stars exact, and per tile its own
// and foreign points and its cells; the colours of the growing phases. With --rays, also the
// visibility counts: each tile walks the rays that may reach its cells through its own
// triangulation, and the bench checks that together they count what the whole triangulation
// counts, cell for cell. With --grow, the tiles grow O in colour phases (tiles/tile_growth.h);
// the bench checks the surface they give together (a closed 2-manifold, exactly) and writes it
// as DIR/initial_tiles<N>.ply, for `manisweep evaluate`.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <unordered_map>
#include <vector>

#include "base/error.h"
#include "base/log.h"
#include "manifold/cell_ray_counts.h"
#include "manifold/manifold_options.h"
#include "manifold/scene_rays.h"
#include "manifold/tile_manifold.h"
#include "mesh/mesh.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "scene/scene_io.h"
#include "tiles/tile_growth.h"
#include "tiles/tile_layout.h"
#include "tiles/tile_stars.h"

namespace {

// The scene's vertices and rays as the tiles start from them (TiledSceneFromPoints), with
// every graded Steiner point kept (--manifold.graded-steiner on): the densest Steiner set, whose
// stars reach farthest across the seams.
ms::ManifoldOptions BenchOptions() {
  ms::ManifoldOptions options;
  options.steiner_graded = ms::GradedSteiner::kOn;
  return options;
}

ms::TiledScene SceneVertices(const ms::Scene& scene) {
  return ms::TiledSceneFromPoints(ms::RayPointsFromScene(scene),
                                  ms::ManifoldCamerasFromScene(scene), BenchOptions());
}

int64_t SteinerPoints(const ms::TiledScene& v) {
  return static_cast<int64_t>(v.points.size()) - v.first_steiner;
}

// The rays a tile counts on the cells it owns (ms::TileManifold), and what that cost.
std::vector<ms::CellRayCount> OwnedCounts(const ms::TiledScene& v, const std::vector<int32_t>& held,
                                          const std::function<bool(int32_t)>& owns,
                                          ms::CellRayCountStats* stats) {
  return ms::TileManifold(v.points, held, owns, v.first_steiner, v.graded, v.cameras, v.rays,
                          BenchOptions(), stats)
      .OwnedCounts();
}

// The whole triangulation's counts: one tile that holds and owns everything.
struct WholeCounts {
  std::vector<ms::CellRayCount> cells;
  ms::CellRayCountStats stats;
};
WholeCounts CountWhole(const ms::TiledScene& v) {
  std::vector<int32_t> all(v.points.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int32_t>(i);
  WholeCounts whole;
  whole.cells = OwnedCounts(
      v, all, [](int32_t) { return true; }, &whole.stats);
  return whole;
}

// Each tile counts the rays on the cells it owns; adds per tile what that cost to `per_tile`
// and returns whether the tiles' counts together are the whole's.
bool CountTileRays(const ms::TiledScene& v, const std::vector<ms::TileHolding>& holdings,
                   const WholeCounts& whole, nlohmann::json* per_tile) {
  std::vector<int> owner(v.points.size(), -1);
  for (size_t t = 0; t < holdings.size(); ++t) {
    for (int32_t id : holdings[t].owned) owner[id] = static_cast<int>(t);
  }
  std::vector<ms::CellRayCount> united;
  for (size_t t = 0; t < holdings.size(); ++t) {
    std::vector<int32_t> held = holdings[t].owned;
    held.insert(held.end(), holdings[t].foreign.begin(), holdings[t].foreign.end());
    ms::CellRayCountStats stats;
    const std::vector<ms::CellRayCount> counts = OwnedCounts(
        v, held, [&](int32_t id) { return owner[id] == static_cast<int>(t); }, &stats);
    united.insert(united.end(), counts.begin(), counts.end());
    (*per_tile)[t]["rays_walked"] = stats.rays_walked;
    (*per_tile)[t]["ray_cell_steps"] = stats.cell_steps;
    (*per_tile)[t]["seconds_rays"] = stats.seconds;
  }
  std::sort(united.begin(), united.end(),
            [](const ms::CellRayCount& a, const ms::CellRayCount& b) { return a.ids < b.ids; });
  return united == whole.cells;
}

// Grows O over the tiles and writes the closed surface they give; the row's growing figures.
nlohmann::json GrowAndWrite(const ms::TiledScene& v, const ms::TileLayout& layout,
                            const ms::TileGrowthOptions& growth, const std::string& dir) {
  const ms::TiledSurface grown = ms::GrowTiles(v, layout, BenchOptions(), growth);
  int64_t outside = 0;
  for (const auto& cells : grown.outside) outside += static_cast<int64_t>(cells.size());
  ms::Mesh mesh;
  mesh.vertices = v.points;
  mesh.faces = grown.faces;
  mesh.RemoveUnreferencedVertices();
  ms::MeshCheckOptions check;
  check.check_self_intersections = false;  // a Delaunay surface: faces meet only at their edges
  const ms::MeshReport report = ms::CheckMesh(mesh, check);
  const std::string path = dir + "/initial_tiles" + std::to_string(layout.num_tiles()) + ".ply";
  ms::WriteMesh(mesh, path);
  std::printf("      grown: %lld cells in O, %zu faces, closed 2-manifold %s, %d rounds, %.1f s\n",
              static_cast<long long>(outside), mesh.faces.size(),
              report.is_closed_manifold ? "yes" : "NO", grown.stats.rounds,
              grown.stats.seconds_growing);
  return {{"band", growth.band},
          {"outside_cells", outside},
          {"surface_faces", mesh.faces.size()},
          {"surface_vertices", mesh.vertices.size()},
          {"closed_manifold", report.is_closed_manifold},
          {"components", report.num_components},
          {"rounds", grown.stats.rounds},
          {"labels_read", grown.stats.labels_read},
          {"seconds_counting", grown.stats.seconds_counting},
          {"seconds_growing", grown.stats.seconds_growing},
          {"mesh", path}};
}

nlohmann::json RunTiles(const ms::TiledScene& v, int tiles, const WholeCounts* whole,
                        const ms::TileGrowthOptions& growth, const std::string& grow_dir) {
  // The split balances the scene's points: the Steiner points fill the enlarged box, whose
  // longest sides across a street would otherwise put seams along it.
  const std::vector<Eigen::Vector3d> scene_points(v.points.begin(),
                                                  v.points.begin() + v.first_steiner);
  const ms::TileLayout layout = ms::TileLayout::Split(scene_points, tiles);
  ms::StarExchangeStats stats;
  const std::vector<ms::TileHolding> holdings =
      ms::ExchangeStarPoints(v.points, v.hull, layout, &stats);
  const std::vector<int> colours = ms::ColourTiles(ms::TileNeighbours(v.points, holdings, layout));
  nlohmann::json per_tile = nlohmann::json::array();
  double worst_ratio = 0;
  for (int t = 0; t < tiles; ++t) {
    const auto& h = holdings[t];
    const double ratio =
        h.owned.empty() ? 0.0 : static_cast<double>(h.foreign.size()) / h.owned.size();
    worst_ratio = std::max(worst_ratio, ratio);
    // The vertex in most of the tile's cells: a large star reaches far across the seams.
    const std::vector<ms::TileCell> cells = ms::OwnedCells(v.points, h);
    std::unordered_map<int32_t, int64_t> cells_at;
    for (const ms::TileCell& cell : cells) {
      for (int32_t id : cell) ++cells_at[id];
    }
    std::pair<int32_t, int64_t> largest = {-1, 0};
    for (const auto& [id, count] : cells_at) {
      if (count > largest.second || (count == largest.second && id < largest.first)) {
        largest = {id, count};
      }
    }
    per_tile.push_back({{"owned", h.owned.size()},
                        {"foreign", h.foreign.size()},
                        {"cells", cells.size()},
                        {"largest_star_vertex", largest.first},
                        {"largest_star_is_steiner", largest.first >= v.first_steiner},
                        {"largest_star_cells", largest.second},
                        {"colour", colours[t]}});
  }
  const int colour_count = *std::max_element(colours.begin(), colours.end()) + 1;
  std::printf("%5d %6d %12lld %12lld %9.3f %9.2f %7d\n", tiles, stats.rounds,
              static_cast<long long>(stats.spheres_asked),
              static_cast<long long>(stats.foreign_points), worst_ratio, stats.seconds,
              colour_count);
  nlohmann::json row = {{"tiles", tiles},
                        {"rounds", stats.rounds},
                        {"spheres_asked", stats.spheres_asked},
                        {"points_sent", stats.points_sent},
                        {"foreign_points", stats.foreign_points},
                        {"worst_foreign_per_owned", worst_ratio},
                        {"seconds_exchange", stats.seconds},
                        {"colours", colour_count}};
  if (whole != nullptr) {
    const bool equal = CountTileRays(v, holdings, *whole, &per_tile);
    std::printf("      ray counts on the tiles' cells %s the whole triangulation's\n",
                equal ? "equal" : "DIFFER FROM");
    row["ray_counts_equal_whole"] = equal;
    row["whole_rays"] = whole->stats.rays;
    row["whole_ray_cell_steps"] = whole->stats.cell_steps;
    row["whole_seconds_rays"] = whole->stats.seconds;
  }
  if (!grow_dir.empty()) row["growing"] = GrowAndWrite(v, layout, growth, grow_dir);
  row["per_tile"] = per_tile;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  ms::InitLogging("bench");
  spdlog::set_level(spdlog::level::warn);
  std::string scene_path, json_path;
  std::vector<int> tile_counts = {1, 2, 4, 8};
  CLI::App cli("What splitting a scene into tiles costs each tile (docs/design/scalability.md)");
  cli.add_option("scene", scene_path, "a scene in any supported format")->required();
  cli.add_option("--tiles", tile_counts, "tile counts, one run each")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bool rays = false;
  cli.add_flag("--rays", rays,
               "also count the viewing rays on each tile's cells and check them against the "
               "whole triangulation's (one thread)");
  std::string grow_dir;
  cli.add_option("--grow", grow_dir,
                 "also grow O over the tiles and write each tile count's surface into this "
                 "directory")
      ->check(CLI::ExistingDirectory);
  ms::TileGrowthOptions growth;
  cli.add_option("--band", growth.band,
                 "growing's bands of weight, each this many times lighter (0: one band)")
      ->capture_default_str();
  growth.threads = 1;  // the growing's seconds are one thread's
  cli.add_option("--threads", growth.threads, "threads for the tiles of a phase (0: one per core)")
      ->capture_default_str();
  cli.add_option("--json", json_path, "write the rows into this JSON file");
  CLI11_PARSE(cli, argc, argv);
  try {
    const ms::TiledScene v = SceneVertices(ms::ReadScene(scene_path));
    std::printf("%lld scene points, %lld Steiner points (%zu on the box)\n",
                static_cast<long long>(v.first_steiner), static_cast<long long>(SteinerPoints(v)),
                v.hull.size());
    std::printf("%5s %6s %12s %12s %9s %9s %7s\n", "tiles", "rounds", "spheres", "foreign",
                "worst f/o", "seconds", "colours");
    WholeCounts whole;
    if (rays) {
      whole = CountWhole(v);
      std::printf("whole triangulation: %lld rays, %lld cell steps, %.1f s\n",
                  static_cast<long long>(whole.stats.rays),
                  static_cast<long long>(whole.stats.cell_steps), whole.stats.seconds);
    }
    nlohmann::json rows = nlohmann::json::array();
    for (int tiles : tile_counts) {
      rows.push_back(RunTiles(v, tiles, rays ? &whole : nullptr, growth, grow_dir));
      rows.back()["scene_points"] = v.first_steiner;
      rows.back()["steiner_points"] = SteinerPoints(v);
      std::fflush(stdout);
    }
    bool counts_differ = false, open_surface = false;
    for (const nlohmann::json& row : rows) {
      counts_differ |= row.contains("ray_counts_equal_whole") && !row["ray_counts_equal_whole"];
      open_surface |= row.contains("growing") && !row["growing"]["closed_manifold"];
    }
    if (!json_path.empty()) {
      std::ofstream json(json_path);
      json << rows.dump(1) << "\n";
      if (!json) throw ms::InputError("cannot write " + json_path);
    }
    if (counts_differ) {
      std::fprintf(stderr, "tiles_bench: the tiles' ray counts differ from the whole's\n");
      return 1;
    }
    if (open_surface) {
      std::fprintf(stderr, "tiles_bench: the tiles' surface is not a closed 2-manifold\n");
      return 1;
    }
  } catch (const ms::InputError& e) {
    std::fprintf(stderr, "tiles_bench: %s\n", e.what());
    return 2;
  }
  return 0;
}
