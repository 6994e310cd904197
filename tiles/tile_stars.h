// Which points each tile must hold so that the Delaunay star of every point it owns is exactly
// that point's star in the triangulation of all points (docs/design/scalability.md, "Tiles").
//
// A tile owns the points its region holds (TileLayout::TileOf). Starting from them, the hull
// and a sparse sample of the rest, it asks the other tiles, round after round, for their points
// inside the circumsphere of every cell around its vertices, until no tile learns a new point:
// then no point it lacks conflicts with those cells, so its stars are the whole
// triangulation's (CGAL's symbolic perturbation makes the triangulation of any subset agree
// with the whole one wherever the empty-sphere test agrees). It keeps only those stars'
// vertices. Every cell of the whole triangulation belongs to the tile owning its smallest point
// id, which holds it exactly: the tiles' cells partition the whole triangulation with no gap
// and no overlap, and a seam is stitched vertex for vertex.
//
// A tile also holds exactly the stars of every vertex of its cells: growing tests whether a
// cell may flip from the labels around its four vertices, which other tiles' cells may share.
//
// Here the tiles exchange in one process; a tile coordinator will answer the same sphere
// queries over the network.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "tiles/tile_layout.h"

namespace ms {

struct TileHolding {
  std::vector<int32_t> owned;    // ids of the points in the tile's region, ascending
  std::vector<int32_t> foreign;  // ids of other tiles' points it holds, ascending
};

struct StarExchangeStats {
  int rounds = 0;              // exchange rounds until no tile learnt a point
  int64_t spheres_asked = 0;   // cells whose circumsphere a tile asked the others about
  int64_t points_sent = 0;     // points handed to a tile that did not hold them
  int64_t foreign_points = 0;  // sum over tiles of foreign points held at the end
  double seconds = 0;
};

// `points` must be pairwise distinct; every tile holds the `hull` points (ids into `points`),
// whose convex hull must contain every other point strictly inside: the scene's Steiner box.
// Throws InputError for a point outside that hull, a repeated point or an id out of range.
std::vector<TileHolding> ExchangeStarPoints(const std::vector<Eigen::Vector3d>& points,
                                            const std::vector<int32_t>& hull,
                                            const TileLayout& layout,
                                            StarExchangeStats* stats = nullptr);

// A cell by the ids of its four points, ascending.
using TileCell = std::array<int32_t, 4>;

// The finite cells of the triangulation of the tile's points (owned and foreign) whose
// smallest point id the tile owns, ascending. With ExchangeStarPoints' holdings these are the
// tile's share of the whole triangulation.
std::vector<TileCell> OwnedCells(const std::vector<Eigen::Vector3d>& points,
                                 const TileHolding& holding);

// The finite cells around every vertex of the tile's owned cells and around its own points,
// ascending: the stars the regularity test reads when a cell of the tile flips. With
// ExchangeStarPoints' holdings every one is a cell of the whole triangulation.
std::vector<TileCell> CellsAroundOwnedCells(const std::vector<Eigen::Vector3d>& points,
                                            const TileHolding& holding);

// For each tile, the tiles owning a cell of those stars (or reading one of its cells there),
// ascending: the tiles whose labels it reads while it grows, and which read its labels.
std::vector<std::vector<int>> TileNeighbours(const std::vector<Eigen::Vector3d>& points,
                                             const std::vector<TileHolding>& holdings,
                                             const TileLayout& layout);

// A colour per tile, no two neighbours alike (greedy, in tile order): tiles of one colour may
// change their labels at the same time, since no star holds cells of two of them.
std::vector<int> ColourTiles(const std::vector<std::vector<int>>& neighbours);

}  // namespace ms
