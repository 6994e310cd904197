// Hooks into the manifold's internals for manifold_test (no CGAL types in this header; they
// stay in manifold_test_hooks.cc, which works on DelaunayManifold::Impl directly).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "manifold/delaunay_manifold.h"

namespace ms::manifold_internal {

using CellVertices = std::array<int32_t, 4>;  // sorted point indices

// Exact: does the open segment (a, b) meet the open tetrahedron? (either orientation)
bool SegmentCrossesTetrahedron(std::array<Eigen::Vector3d, 4> tet, const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b);

// Finite cells of the Delaunay triangulation of `points` (no Steiner points).
std::vector<CellVertices> DelaunayCells(const std::vector<Eigen::Vector3d>& points);

// Is points[v] a regular vertex of the boundary of O when exactly `outside` cells (of
// DelaunayCells(points)) are in O?
bool IsVertexRegular(const std::vector<Eigen::Vector3d>& points,
                     const std::vector<CellVertices>& outside, int32_t v);

// Flips random cells of a triangulation of `points` whenever both regularity tests allow it,
// comparing the link-walk test with the exhaustive one on every vertex of every candidate.
// Returns the number of disagreements; *checked receives the number of comparisons.
int64_t RegularityTestMismatches(const std::vector<Eigen::Vector3d>& points, uint32_t seed,
                                 int64_t* checked);

// Puts in O the finite cells of the triangulation of `points` whose centroid `in_o` accepts,
// then compares, on every vertex, the link-walk regularity test (started from the whole star,
// and from one cell of it) with the exhaustive one.
struct LinkWalkComparison {
  int64_t checked = 0, mismatches = 0, regular = 0, irregular = 0;
  int64_t largest_star = 0;           // cells around the vertex with the most
  bool largest_star_regular = false;  // that vertex's verdict
};
LinkWalkComparison CompareLinkWalk(const std::vector<Eigen::Vector3d>& points,
                                   const std::function<bool(const Eigen::Vector3d&)>& in_o);

// Cells crossed by the open segment camera -> points[target] in a manifold built from
// `points` (with Steiner points, ids -1-k): as found by the walk and by testing every cell.
void CrossedCells(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& camera,
                  int32_t target, std::vector<CellVertices>* walked,
                  std::vector<CellVertices>* brute_force);

// Counts `rays` crossings of one cell spreading across its face 0 (the neighbour there finite),
// on `threads` threads at once (CountCrossingConcurrently, tallies merged) or with CountCrossing
// for 1, then one more cell of the same triangulation destroyed and rebuilt: what the labels
// read back.
struct SpreadCounts {
  int64_t spread = 0;           // CellLabels::Spread of the cell's face 0
  double neighbour_weight = 0;  // CellLabels::Weight of the neighbour across it (w1 = 1, w2 = 1)
  int64_t after_forget = 0;     // Spread of face 0 once its counts were forgotten and reset
};
SpreadCounts CountSpreads(int64_t rays, int threads = 1);

// Two copies of a manifold built from `points`, O shrunk at the same random cells, then grown
// back from its boundary in parts with single cells joined between them, then cells taken out
// of O, each time followed by growing: one copy keeps its refusals aside between growings
// (GrowShrink::Refusals::Kind::kIndexed, woken by the flips), the other queues them all again
// each time (kRequeued). What differs between the two.
struct KeptRefusalsComparison {
  int64_t joins = 0;             // single cells joined between growings
  int64_t shrinks = 0;           // cells taken out of O
  int64_t grown = 0;             // cells that joined by growing
  int64_t refusals = 0;          // refusals kept after growing back
  int64_t order_mismatches = 0;  // places where the cells joined, in order, differ
  int64_t label_mismatches = 0;  // cells whose label differs at the end
};
KeptRefusalsComparison CompareKeptRefusals(const std::vector<ManifoldCamera>& cameras,
                                           const std::vector<RayPoint>& points, uint32_t seed);

// GrowShrink::JoinPocketWithPinches on every pocket next to O after O lost a third of its cells
// (seeded), each checked at once: a join leaves the pocket in O and every vertex regular, a
// failure changes no label.
struct PinchJoinCounts {
  int64_t pockets = 0;
  int64_t whole = 0;        // joined with no matter
  int64_t with_pieces = 0;  // joined with pinching matter
  int64_t failed = 0;
  int64_t whole_piece_rounds = 0;  // rounds that took a whole piece where O touches itself
  int64_t problems = 0;  // joins that broke the manifold or missed a pocket cell, failures
                         // that changed a label
};
PinchJoinCounts JoinPocketsWithPinches(const std::vector<ManifoldCamera>& cameras,
                                       const std::vector<RayPoint>& points, uint32_t seed);

}  // namespace ms::manifold_internal
