// The manifold tests of growing and shrinking (paper section 2.1, docs/design/manifold.md): does
// the boundary of O stay a 2-manifold when one cell flips into or out of O? A fast (V,E,F) count
// first, then an exact link test per vertex; and the exhaustive vertex test that Validate and
// the tests check the fast ones against. Internal to manifold/.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "manifold/cell_labels.h"
#include "manifold/triangulation.h"

namespace ms::manifold_detail {

class Regularity {
 public:
  struct Counts {
    // Flip tests, those the (V,E,F) test could not decide, link edges walked by the link test.
    int64_t fast = 0, full = 0, link_steps = 0;
  };

  // `dt` must outlive this object. The labels are read from CellInfo::outside (InO) and the
  // per-vertex counts that CellLabels::SetOutside keeps.
  explicit Regularity(const Delaunay& dt) : dt_(dt) {}

  // Would flipping t (into O if it is outside O, out of O otherwise) keep the surface
  // manifold? (V,E,F) test, then the link test on every vertex of t. Counted in counts().
  bool FlipKeepsManifold(const Cell_handle& t);

  // Is v still regular after flipping t (a cell around v)? Exact and local; assumes v is
  // regular now (the invariant).
  bool VertexRegularAfterFlip(const Vertex_handle& v, const Cell_handle& t);

  // Exhaustive: the link of v is one closed cycle or empty, with `flipped` taken with its
  // label inverted (Cell_handle(): none).
  bool VertexRegular(const Vertex_handle& v, const Cell_handle& flipped);

  // The same verdict as VertexRegular(v, Cell_handle()) for a vertex with a large star: walks
  // the link from a surface face of one of `near` (cells around v), checking each link vertex's
  // degree by circling its edge to v, and compares the length with v's surface-face count.
  // Costs O(link x edge degree) instead of O(star); scans the star when no cell of `near`
  // has a surface face at v.
  bool VertexRegularByLinkWalk(const Vertex_handle& v, const std::vector<Cell_handle>& near);

  const Counts& counts() const { return counts_; }

 private:
  const Delaunay& dt_;
  Counts counts_;
  // Reused by VertexRegular (no allocation in the hot path).
  std::vector<Cell_handle> cells_;
  std::vector<std::pair<uintptr_t, uintptr_t>> half_edges_;  // (vertex address, link neighbour)
};

}  // namespace ms::manifold_detail
