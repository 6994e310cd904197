// One tile's part of the manifold (docs/design/scalability.md, "Tiles"): the Delaunay
// triangulation of the points the tile holds, the visibility counts of the cells around its own,
// and the labels of O. The tile owns the cells whose smallest point id it owns; it may flip
// those and the cells whose four vertices are vertices of its own cells, since it holds the
// whole triangulation's stars of those vertices (tiles/tile_stars.h): each flip is tested on
// exactly the labels the whole triangulation would read. Every other cell is frozen: its label
// is set from the tiles that flip it, and it is never free here. Tiles that never share a star
// may flip at the same time, and their surfaces together are one 2-manifold.
//
// Growing here is the build's: heaviest-first growing (GrowShrink::Grow), the repairs of
// cameras left in the matter and the pocket joins.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "manifold/cell_ray_counts.h"
#include "manifold/manifold_options.h"

namespace ms {

class TileManifold {
 public:
  using Cell = std::array<int32_t, 4>;  // a cell by its point ids, ascending
  using Face = std::array<int32_t, 3>;  // normal into O, the smallest id first

  // A free cell to start growing from, and its weight.
  struct Seed {
    double weight = 0;
    Cell cell{};
  };

  // Triangulates points[held] (pairwise distinct; their hull holds the cameras) and counts
  // the viewing rays on the cells around its own cells' vertices (cell_ray_counts.h;
  // ray_stats, when given, gets what that cost). The tile owns the cells whose smallest
  // id it owns (owns(id), kept: what it reads must outlive the tile); ids from first_steiner
  // on are Steiner points (with `graded`, a cell of Steiner points only is free, as
  // CellLabels). Throws InputError for a repeated point, a camera outside the hull or a ray out
  // of range.
  TileManifold(const std::vector<Eigen::Vector3d>& points, const std::vector<int32_t>& held,
               const std::function<bool(int32_t)>& owns, int32_t first_steiner, bool graded,
               const std::vector<Eigen::Vector3d>& cameras, const std::vector<ViewingRay>& rays,
               const ManifoldOptions& options, CellRayCountStats* ray_stats = nullptr);
  ~TileManifold();
  TileManifold(TileManifold&&) noexcept;
  TileManifold& operator=(TileManifold&&) noexcept;

  // The heaviest owned free cell outside O with no vertex touching O (ties: the smaller ids).
  std::optional<Seed> HeaviestFreeCell() const;
  // Grows O over the cells it may flip of at least `min_weight`, from `seed` (a cell the tile
  // owns) and from every such free cell beside O. Returns the cells added, in the order added.
  std::vector<Cell> Grow(const std::optional<Cell>& seed = std::nullopt, double min_weight = 0);
  // Brings the cameras whose start the tile may flip, and which growing left in the matter,
  // back into free space (GrowShrink::FreeEnclosedCameras). Returns the cells added.
  std::vector<Cell> FreeEnclosedCameras();
  // Joins the pockets of free space next to O that growing could not enter, and grows on from
  // them (GrowShrink::JoinFreePockets; frozen cells never join). Returns the cells added.
  std::vector<Cell> JoinPockets();
  // Labels cells as other tiles flipped them: those of `cells` that the tile reads (the cells
  // around the vertices of its own cells) go into O, or out of it. Others are ignored.
  // Returns the labels it changed.
  int64_t SetLabels(const std::vector<Cell>& cells, bool outside);

  // The rays counted on each owned cell, sorted by ids: the whole triangulation's counts where
  // the tile holds its stars (tiles/tile_stars.h).
  std::vector<CellRayCount> OwnedCounts() const;
  // The owned cells in O, ascending.
  std::vector<Cell> OutsideCells() const;
  // The faces between an owned cell in O and a cell outside O.
  std::vector<Face> SurfaceFaces() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ms
