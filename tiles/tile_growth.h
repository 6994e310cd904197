// Growing O over tiles (docs/design/scalability.md, "Tiles"): every tile triangulates the
// points it holds (tile_stars.h), counts the viewing rays on the cells around its own
// (manifold/cell_ray_counts.h) and grows its own cells (manifold/tile_manifold.h), reading the
// other tiles' labels on the cells it does not own. Tiles grow in phases by colour: tiles of
// one colour share no star, so each flip is tested on the labels the whole triangulation has,
// and the tiles' surfaces together are one closed 2-manifold, stitched by point ids. Growing
// goes in bands of weight, heaviest first, each band in rounds of phases until a round adds
// nothing; then each tile brings the cameras left in the matter back into free space and joins
// its pockets of free space, in rounds of phases too.
//
// The growing order differs from one coordinator's (one queue over all cells), so the surface
// may differ from the untiled one; it is the same with any number of workers.
//
// Here the tiles run in one process, those of a phase on threads; a tile coordinator will send its
// labels to its neighbours at the end of its phase.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "manifold/cell_ray_counts.h"
#include "manifold/delaunay_manifold.h"
#include "manifold/manifold_options.h"
#include "manifold/tile_manifold.h"
#include "tiles/tile_layout.h"

namespace ms {

// What the tiles start from: the triangulation's vertices and the rays.
struct TiledScene {
  std::vector<Eigen::Vector3d> points;  // the scene's points, then the Steiner points
  int32_t first_steiner = 0;            // the first Steiner point's id
  std::vector<int32_t> hull;            // the Steiner box points, which every tile holds
  bool graded = false;                  // a cell of Steiner points only is free (CellLabels)
  std::vector<Eigen::Vector3d> cameras;
  std::vector<ViewingRay> rays;
};

// Growing goes in bands of weight, heaviest first, each `band` times lighter than the one
// before; all tiles grow a band until it adds nothing, which follows the order of one queue over
// all cells to within that factor. 0: one band (each tile grows all it can in turn), for
// comparison: on the 60-view streets its initial meshes measured 0.89-1.11x the untiled MAE,
// bands of 1.25 0.99-1.01x (docs/design/scalability.md, "Growing in tiles").
struct TileGrowthOptions {
  double band = 1.25;
  // Threads for the tiles of one phase (and for building the tiles); 0: one per core. The
  // result is the same with any number.
  int threads = 0;
};

// The tiles' start from a scene's points and cameras, as DelaunayManifold::Build starts: the
// same Steiner points and near-duplicates merged the same way (manifold/manifold_vertices.h).
// The points kept are numbered in input order; a merged point's rays end at the point it
// merges into.
TiledScene TiledSceneFromPoints(const std::vector<RayPoint>& points,
                                const std::vector<ManifoldCamera>& cameras,
                                const ManifoldOptions& options);

struct TileGrowthStats {
  int colours = 0;
  int rounds = 0;           // rounds over the colours until one added nothing, all bands
  int camera_rounds = 0;    // rounds of camera repairs, the last joining none
  int pocket_rounds = 0;    // rounds of pocket joins, the last joining none
  int64_t labels_read = 0;  // frozen cells set in O, over all phases and tiles
  int64_t foreign_points = 0;
  double seconds_exchange = 0, seconds_counting = 0, seconds_growing = 0;
};

struct TiledSurface {
  std::vector<std::array<int32_t, 3>> faces;  // by point id, normals into O, sorted
  std::vector<std::vector<std::array<int32_t, 3>>> tile_faces;  // per tile, its cells' faces
  std::vector<std::vector<TileManifold::Cell>> outside;         // per tile, its cells in O
  TileGrowthStats stats;
};

TiledSurface GrowTiles(const TiledScene& scene, const TileLayout& layout,
                       const ManifoldOptions& options, const TileGrowthOptions& growth = {});

}  // namespace ms
