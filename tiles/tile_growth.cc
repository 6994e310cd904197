#include "tiles/tile_growth.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <utility>

#include "base/error.h"
#include "base/parallel_for.h"
#include "manifold/manifold_vertices.h"
#include "manifold/point_merging.h"
#include "tiles/tile_stars.h"

namespace ms {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A tile's triangulation with its ray counts (manifold/tile_manifold.h).
TileManifold MakeTile(const TiledScene& scene, const TileHolding& holding,
                      const std::vector<int>& owner, int tile, const ManifoldOptions& options) {
  std::vector<int32_t> held = holding.owned;
  held.insert(held.end(), holding.foreign.begin(), holding.foreign.end());
  return TileManifold(
      scene.points, held, [&owner, tile](int32_t id) { return owner[id] == tile; },
      scene.first_steiner, scene.graded, scene.cameras, scene.rays, options);
}

struct SeedInTile {
  int tile = -1;
  TileManifold::Seed seed;
};

// The heaviest free cell with no vertex touching O, over all tiles (ties: the smaller ids).
std::optional<SeedInTile> HeaviestFreeCell(const std::vector<TileManifold>& tiles) {
  std::optional<SeedInTile> best;
  for (size_t t = 0; t < tiles.size(); ++t) {
    const std::optional<TileManifold::Seed> s = tiles[t].HeaviestFreeCell();
    if (!s) continue;
    if (!best || s->weight > best->seed.weight ||
        (s->weight == best->seed.weight && s->cell < best->seed.cell)) {
      best = SeedInTile{static_cast<int>(t), *s};
    }
  }
  return best;
}

}  // namespace

TiledScene TiledSceneFromPoints(const std::vector<RayPoint>& points,
                                const std::vector<ManifoldCamera>& cameras,
                                const ManifoldOptions& options) {
  Eigen::Vector3d lo, hi;
  BoundPointsAndCameras(points, cameras, &lo, &hi);
  const SteinerPoints steiner = PlaceSteinerPoints(points, cameras, lo, hi, options);
  const std::vector<int32_t> representative =
      NearDuplicateRepresentatives(points, cameras, InputMergeTolerance(steiner.points, options));
  TiledScene scene;
  std::vector<int32_t> id_of(points.size(), -1);
  // A point at exactly an earlier kept point's position (no merge tolerance) is that point.
  std::map<std::array<double, 3>, int32_t> kept_at;
  for (size_t i = 0; i < points.size(); ++i) {
    if (representative[i] != static_cast<int32_t>(i)) {
      id_of[i] = id_of[representative[i]];
      continue;
    }
    const Eigen::Vector3d& p = points[i].position;
    const auto [at, added] =
        kept_at.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, scene.points.size());
    if (added) scene.points.push_back(p);
    id_of[i] = at->second;
  }
  scene.first_steiner = static_cast<int32_t>(scene.points.size());
  const size_t box = steiner.points.size() - static_cast<size_t>(steiner.graded);
  for (size_t k = 0; k < steiner.points.size(); ++k) {
    if (k < box) scene.hull.push_back(static_cast<int32_t>(scene.points.size()));
    scene.points.push_back(steiner.points[k]);
  }
  scene.graded = SteinerCellsFree(options);
  for (const ManifoldCamera& c : cameras) scene.cameras.push_back(c.center);
  for (size_t i = 0; i < points.size(); ++i) {
    for (int32_t c : points[i].cameras) scene.rays.push_back({c, id_of[i]});
  }
  return scene;
}

namespace {

// The tiles' rounds of phases: each phase, the tiles of one colour read the cells flipped since
// their last phase and then work at once, each on its own triangulation; what they flipped is
// appended in tile order, so the result does not depend on the threads.
class PhaseRounds {
 public:
  PhaseRounds(std::vector<TileManifold>* tiles, std::vector<int> colour, int threads,
              TileGrowthStats* stats)
      : tiles_(*tiles),
        colour_(std::move(colour)),
        threads_(threads),
        stats_(*stats),
        read_up_to_(tiles->size(), 0) {}

  // Every tile reads what it has not read yet.
  void ReadAll() {
    for (size_t t = 0; t < tiles_.size(); ++t) Read(static_cast<int>(t));
  }

  // One round over the colours from `first_colour` on: step(tile) works on a tile and returns
  // the cells it flipped. Returns whether any tile flipped one.
  bool Round(int first_colour, const std::function<std::vector<TileManifold::Cell>(int)>& step) {
    bool flipped = false;
    for (int k = 0; k < stats_.colours; ++k) {
      std::vector<int> phase;
      for (size_t t = 0; t < tiles_.size(); ++t) {
        if (colour_[t] == (first_colour + k) % stats_.colours) phase.push_back(static_cast<int>(t));
      }
      for (int t : phase) Read(t);
      std::vector<std::vector<TileManifold::Cell>> cells(phase.size());
      ParallelFor(
          phase.size(), [&](size_t i) { cells[i] = step(phase[i]); }, threads_);
      for (const std::vector<TileManifold::Cell>& c : cells) {
        added_.insert(added_.end(), c.begin(), c.end());
        flipped |= !c.empty();
      }
    }
    return flipped;
  }

 private:
  void Read(int t) {
    const std::vector<TileManifold::Cell> unread(added_.begin() + read_up_to_[t], added_.end());
    stats_.labels_read += tiles_[t].SetLabels(unread, true);
    read_up_to_[t] = added_.size();
  }

  std::vector<TileManifold>& tiles_;
  const std::vector<int> colour_;
  const int threads_;
  TileGrowthStats& stats_;
  // The cells the tiles flipped, in order; each tile has read them up to its mark. A tile
  // coordinator would get them from its neighbours at the end of their phase.
  std::vector<TileManifold::Cell> added_;
  std::vector<size_t> read_up_to_;
};

// Grows one component from `seed`, in bands of weight, heaviest first, each grown by all tiles
// until a round adds nothing.
void GrowInBands(const SeedInTile& seed, const std::vector<int>& colour,
                 const ManifoldOptions& options, const TileGrowthOptions& growth,
                 std::vector<TileManifold>* tiles, PhaseRounds* rounds, TileGrowthStats* stats) {
  std::optional<TileManifold::Cell> seed_cell = seed.seed.cell;  // grown from once
  for (double band = growth.band > 0 ? seed.seed.weight / growth.band : 0.0;; band /= growth.band) {
    const double min_weight = band < options.free_threshold ? 0.0 : band;
    bool grew = true;
    while (grew) {
      ++stats->rounds;
      // The seed's colour first.
      grew = rounds->Round(colour[seed.tile], [&](int t) {
        return (*tiles)[t].Grow(t == seed.tile ? seed_cell : std::nullopt, min_weight);
      });
      seed_cell.reset();
    }
    if (min_weight == 0) break;
  }
}

// The tiles, each with its triangulation and ray counts, built at once.
std::vector<TileManifold> MakeTiles(const TiledScene& scene,
                                    const std::vector<TileHolding>& holdings,
                                    const std::vector<int>& owner, const ManifoldOptions& options,
                                    int threads) {
  std::vector<std::optional<TileManifold>> made(holdings.size());
  ParallelFor(
      holdings.size(),
      [&](size_t t) {
        made[t].emplace(MakeTile(scene, holdings[t], owner, static_cast<int>(t), options));
      },
      threads);
  std::vector<TileManifold> tiles;
  for (std::optional<TileManifold>& tile : made) tiles.push_back(std::move(*tile));
  return tiles;
}

}  // namespace

TiledSurface GrowTiles(const TiledScene& scene, const TileLayout& layout,
                       const ManifoldOptions& options, const TileGrowthOptions& growth) {
  if (!(growth.band == 0 || growth.band > 1)) {
    throw InputError("tiles: the growing band must be 0 (none) or above 1");
  }
  // A tile decides free space by the threshold of its own cells' weights only.
  if (options.visibility != FreeSpaceRule::kThreshold || options.behind_ratio > 0) {
    throw InputError(
        "tiles: --manifold.visibility cut and --manifold.behind-ratio are not built for tiles "
        "(a tile weighs its cells by the paper's threshold)");
  }
  TiledSurface result;
  TileGrowthStats& stats = result.stats;
  auto start = std::chrono::steady_clock::now();
  StarExchangeStats exchange;
  const std::vector<TileHolding> holdings =
      ExchangeStarPoints(scene.points, scene.hull, layout, &exchange);
  stats.foreign_points = exchange.foreign_points;
  std::vector<int> colour = ColourTiles(TileNeighbours(scene.points, holdings, layout));
  stats.colours = *std::max_element(colour.begin(), colour.end()) + 1;
  std::vector<int> owner(scene.points.size(), -1);
  for (int t = 0; t < layout.num_tiles(); ++t) {
    for (int32_t id : holdings[t].owned) owner[id] = t;
  }
  stats.seconds_exchange = SecondsSince(start);

  start = std::chrono::steady_clock::now();
  std::vector<TileManifold> tiles = MakeTiles(scene, holdings, owner, options, growth.threads);
  stats.seconds_counting = SecondsSince(start);

  start = std::chrono::steady_clock::now();
  PhaseRounds rounds(&tiles, colour, growth.threads, &stats);
  // One component from the heaviest free cell (with grow_all_components, then one from the
  // heaviest free cell of each further one), as GrowShrink::GrowFromHeaviest.
  for (;;) {
    rounds.ReadAll();
    const std::optional<SeedInTile> seed = HeaviestFreeCell(tiles);
    if (!seed) break;
    GrowInBands(*seed, colour, options, growth, &tiles, &rounds, &stats);
    if (!options.grow_all_components) break;
  }
  // Then, as the untiled build, cameras left in the matter and pockets of free space that
  // growing could not enter: each tile those it may flip, in the same phases, until no tile
  // joins one.
  for (bool joined = true; joined;) {
    ++stats.camera_rounds;
    joined = rounds.Round(0, [&](int t) { return tiles[t].FreeEnclosedCameras(); });
  }
  for (bool joined = true; joined;) {
    ++stats.pocket_rounds;
    joined = rounds.Round(0, [&](int t) { return tiles[t].JoinPockets(); });
  }
  for (const TileManifold& tile : tiles) {
    result.outside.push_back(tile.OutsideCells());
    result.tile_faces.push_back(tile.SurfaceFaces());
    result.faces.insert(result.faces.end(), result.tile_faces.back().begin(),
                        result.tile_faces.back().end());
  }
  std::sort(result.faces.begin(), result.faces.end());
  stats.seconds_growing = SecondsSince(start);
  return result;
}

}  // namespace ms
