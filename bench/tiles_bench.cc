// What splitting a scene into tiles costs each tile (docs/design/scalability.md, "Tiles"):
//   tiles_bench SCENE [--tiles 1 2 4 8] [--json FILE]
// The vertices are the scene's points (exact repeats once) and the Steiner points the manifold
// adds with its default options: the box grid (which every tile holds) and the graded points in
// the empty space, all of them (the manifold keeps those hidden in every view). For each tile
// count: the k-d layout, the exchange that makes every tile's stars exact, and per tile its own
// and foreign points and its cells; the colours of the growing phases.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <unordered_map>
#include <vector>

#include "base/error.h"
#include "base/log.h"
#include "manifold/manifold_options.h"
#include "manifold/steiner_points.h"
#include "scene/scene_io.h"
#include "tiles/tile_layout.h"
#include "tiles/tile_stars.h"

namespace {

struct Vertices {
  std::vector<Eigen::Vector3d> points;
  std::vector<int32_t> hull;  // the Steiner box grid
  int64_t scene_points = 0, steiner_points = 0;
};

Vertices SceneVertices(const ms::Scene& scene) {
  Vertices v;
  std::vector<Eigen::Vector3d> data;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const ms::ScenePoint& p : scene.points) data.push_back(p.position);
  std::sort(data.begin(), data.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  data.erase(std::unique(data.begin(), data.end()), data.end());
  for (const Eigen::Vector3d& p : data) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (const ms::View& view : scene.views) {
    lo = lo.cwiseMin(view.Center());
    hi = hi.cwiseMax(view.Center());
  }
  // The manifold's default Steiner options, read from its option group, not copied.
  const ms::ManifoldOptions defaults;
  ms::SteinerOptions steiner;
  steiner.margin = defaults.steiner_margin;
  steiner.grid = defaults.steiner_grid;
  steiner.graded = defaults.steiner_graded != ms::GradedSteiner::kOff;
  steiner.clearance = defaults.steiner_clearance;
  steiner.min_spacing_factor = defaults.steiner_min_spacing;
  const ms::SteinerPoints made = ms::MakeSteinerPoints(lo, hi, data, steiner);
  v.scene_points = static_cast<int64_t>(data.size());
  v.steiner_points = static_cast<int64_t>(made.points.size());
  v.points = std::move(data);
  const size_t box = made.points.size() - static_cast<size_t>(made.graded);
  for (size_t k = 0; k < made.points.size(); ++k) {
    if (k < box) v.hull.push_back(static_cast<int32_t>(v.points.size()));
    v.points.push_back(made.points[k]);
  }
  return v;
}

nlohmann::json RunTiles(const Vertices& v, int tiles) {
  // The split balances the scene's points: the Steiner points fill the enlarged box, whose
  // longest sides across a street would otherwise put seams along it.
  const std::vector<Eigen::Vector3d> scene_points(v.points.begin(),
                                                  v.points.begin() + v.scene_points);
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
                        {"largest_star_is_steiner", largest.first >= v.scene_points},
                        {"largest_star_cells", largest.second},
                        {"colour", colours[t]}});
  }
  const int colour_count = *std::max_element(colours.begin(), colours.end()) + 1;
  std::printf("%5d %6d %12lld %12lld %9.3f %9.2f %7d\n", tiles, stats.rounds,
              static_cast<long long>(stats.spheres_asked),
              static_cast<long long>(stats.foreign_points), worst_ratio, stats.seconds,
              colour_count);
  return {{"tiles", tiles},
          {"rounds", stats.rounds},
          {"spheres_asked", stats.spheres_asked},
          {"points_sent", stats.points_sent},
          {"foreign_points", stats.foreign_points},
          {"worst_foreign_per_owned", worst_ratio},
          {"seconds_exchange", stats.seconds},
          {"colours", colour_count},
          {"per_tile", per_tile}};
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
  cli.add_option("--json", json_path, "write the rows into this JSON file");
  CLI11_PARSE(cli, argc, argv);
  try {
    const Vertices v = SceneVertices(ms::ReadScene(scene_path));
    std::printf("%lld scene points, %lld Steiner points (%zu on the box)\n",
                static_cast<long long>(v.scene_points), static_cast<long long>(v.steiner_points),
                v.hull.size());
    std::printf("%5s %6s %12s %12s %9s %9s %7s\n", "tiles", "rounds", "spheres", "foreign",
                "worst f/o", "seconds", "colours");
    nlohmann::json rows = nlohmann::json::array();
    for (int tiles : tile_counts) {
      rows.push_back(RunTiles(v, tiles));
      rows.back()["scene_points"] = v.scene_points;
      rows.back()["steiner_points"] = v.steiner_points;
      std::fflush(stdout);
    }
    if (!json_path.empty()) {
      std::ofstream json(json_path);
      json << rows.dump(1) << "\n";
      if (!json) throw ms::InputError("cannot write " + json_path);
    }
  } catch (const ms::InputError& e) {
    std::fprintf(stderr, "tiles_bench: %s\n", e.what());
    return 2;
  }
  return 0;
}
