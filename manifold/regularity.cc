#include "manifold/regularity.h"

#include <algorithm>
#include <iterator>

namespace ms::manifold_detail {

// Fast test first (Lhuillier): count the vertices V, edges E and faces F that t shares with
// the side it joins; (0,0,0), (3,3,1), (4,5,2), (4,6,3) and (4,6,4) are always safe. V and F
// are O(1); E is needed only to tell (4,5,2) from (4,6,2). Otherwise the exact test: every
// vertex of t must stay regular.
bool Regularity::FlipKeepsManifold(const Cell_handle& t) {
  const bool joining_outside = !t->info().outside;
  const auto on_target_side = [&](const Cell_handle& c) {
    return c != t && (joining_outside ? InO(dt_, c) : !InO(dt_, c));
  };
  int F = 0, shared[4], num_shared = 0;
  for (int i = 0; i < 4; ++i) {
    if (on_target_side(t->neighbor(i))) {
      ++F;
      shared[num_shared++] = i;
    }
  }
  int V = 0;
  for (int i = 0; i < 4; ++i) {
    const VertexInfo& info = t->vertex(i)->info();
    // t itself is on neither count of the side it joins.
    V += joining_outside ? info.outside_cells > 0 : info.cells - info.outside_cells > 0;
  }
  ++counts_.fast;
  // With V = 3 and F = 1 the fourth vertex touches nothing, so E = 3; with F >= 3 every edge
  // lies on a shared face, so E = 6. With F = 2, E = 5 iff the edge joining the two vertices
  // opposite the shared faces touches nothing.
  if ((V == 0 && F == 0) || (V == 3 && F == 1) || (V == 4 && F >= 3)) return true;
  if (V == 4 && F == 2) {
    auto circ = dt_.incident_cells(t, shared[0], shared[1]), done = circ;
    bool touches = false;
    do {
      touches = on_target_side(circ);
    } while (!touches && ++circ != done);
    if (!touches) return true;
  }
  ++counts_.full;
  for (int i = 0; i < 4; ++i) {
    if (!VertexRegularAfterFlip(t->vertex(i), t)) return false;
  }
  return true;
}

// The link of v (the edges opposite v in the surface faces around it) is a single simple cycle
// or empty before the flip (the invariant). Flipping t toggles exactly the three link edges
// w1w2, w2w3, w3w1 that t's faces at v contribute. With k of them on the link now, the new
// link is a single cycle or empty iff:
//   k = 0: the link is empty (else a second cycle or a vertex of degree 4 appears);
//   k = 1: say w1w2: it is replaced by w1-w3-w2, fine iff w3 is not on the link already;
//   k = 2: the path w1-w2-w3 is replaced by the edge w1w3: always fine;
//   k = 3: the link was exactly that triangle and becomes empty: fine.
// VertexRegular (the exhaustive criterion) is cross-checked against this in tests.
bool Regularity::VertexRegularAfterFlip(const Vertex_handle& v, const Cell_handle& t) {
  const int iv = t->index(v);
  const bool t_outside = InO(dt_, t);
  int k = 0, w3 = -1;
  for (int i = 0; i < 4; ++i) {
    if (i == iv) continue;
    // Face i of t (opposite vertex i) contains v; it is on the surface iff labels differ.
    if (t_outside != InO(dt_, t->neighbor(i))) {
      ++k;
      w3 = i;  // with k = 1: the surface face is the one opposite w3
    }
  }
  switch (k) {
    case 0:
      return v->info().surface_faces == 0;
    case 1: {
      // Is the edge (v, w3) on the surface (some label change around it)?
      auto circ = dt_.incident_cells(t, iv, w3), done = circ;
      const bool first = InO(dt_, circ);
      bool on_surface = false;
      while (!on_surface && ++circ != done) on_surface = InO(dt_, circ) != first;
      ++counts_.link_steps;
      return !on_surface;
    }
    default:
      return true;
  }
}

// A vertex is regular when the edges opposite to it in the surface faces around it form one
// closed cycle (or there are none).
bool Regularity::VertexRegular(const Vertex_handle& v, const Cell_handle& flipped) {
  const auto label = [&](const Cell_handle& c) {
    return c == flipped ? !InO(dt_, c) : InO(dt_, c);
  };
  std::vector<Cell_handle>& around = cells_;
  around.clear();
  dt_.incident_cells(v, std::back_inserter(around));
  // Each link edge pq as the half-edges (p, q) and (q, p), sorted by their first vertex: the
  // degree test and the cycle walk then cost O(L log L), not O(L^2). Vertices with huge stars
  // (the box's Steiner points) have links of thousands of edges.
  std::vector<std::pair<uintptr_t, uintptr_t>>& half_edges = half_edges_;
  half_edges.clear();
  for (const Cell_handle& c : around) {
    if (!label(c)) continue;
    for (int i = 0; i < 4; ++i) {
      if (c->vertex(i) == v || label(c->neighbor(i))) continue;
      uintptr_t ends[2];
      int n = 0;
      for (int j = 0; j < 4; ++j) {
        if (j != i && c->vertex(j) != v) ends[n++] = reinterpret_cast<uintptr_t>(&*c->vertex(j));
      }
      half_edges.emplace_back(ends[0], ends[1]);
      half_edges.emplace_back(ends[1], ends[0]);
    }
  }
  if (half_edges.empty()) return true;
  std::sort(half_edges.begin(), half_edges.end());
  // Every link vertex must have degree 2: its half-edges come in exactly one pair.
  const size_t num_half_edges = half_edges.size();
  for (size_t k = 0; k < num_half_edges; k += 2) {
    if (half_edges[k].first != half_edges[k + 1].first) return false;
    if (k + 2 < num_half_edges && half_edges[k + 2].first == half_edges[k].first) return false;
  }
  // Walk the cycle from the first vertex; it must use every edge.
  const size_t num_edges = num_half_edges / 2;
  const uintptr_t first = half_edges[0].first;
  uintptr_t previous = first;
  uintptr_t current = half_edges[0].second;
  size_t length = 1;
  while (current != first) {
    const auto at = std::lower_bound(half_edges.begin(), half_edges.end(),
                                     std::make_pair(current, uintptr_t{0}));
    // at and at + 1 are current's two half-edges (degrees are all 2).
    const uintptr_t next = at->second != previous ? at->second : (at + 1)->second;
    if (next == previous) return false;  // both lead back: a doubled edge
    previous = current;
    current = next;
    if (++length > num_edges) return false;
  }
  return length == num_edges;
}

bool Regularity::VertexRegularByLinkWalk(const Vertex_handle& v,
                                         const std::vector<Cell_handle>& near) {
  const int32_t num_edges = v->info().surface_faces;
  if (num_edges == 0) return true;
  // A start: a surface face (v, first, current) of a cell of `near`.
  Cell_handle cell;
  Vertex_handle first, current;
  for (const Cell_handle& c : near) {
    int iv = 0;
    if (!c->has_vertex(v, iv)) continue;
    for (int i = 0; i < 4 && cell == Cell_handle(); ++i) {
      if (i == iv || InO(dt_, c) == InO(dt_, c->neighbor(i))) continue;
      cell = c;
      for (int j = 0; j < 4; ++j) {
        if (j == iv || j == i) continue;
        (first == Vertex_handle() ? first : current) = c->vertex(j);
      }
    }
    if (cell != Cell_handle()) break;
  }
  if (cell == Cell_handle()) return VertexRegular(v, Cell_handle());
  // Circle the edge (v, current): its surface faces are where the label changes between
  // consecutive cells; a link vertex has degree 2 iff there are exactly two, one of them the
  // face we came by. Faces are unique in a triangulation, so the other leads on.
  Vertex_handle previous = first;
  int32_t length = 1;
  while (current != first) {
    Vertex_handle next;
    Cell_handle next_cell;
    int changes = 0;
    auto circ = dt_.incident_cells(cell, cell->index(v), cell->index(current)), done = circ;
    do {
      const Cell_handle a = circ;
      auto successor = circ;
      const Cell_handle b = ++successor;
      if (InO(dt_, a) == InO(dt_, b)) continue;
      if (++changes > 2) return false;
      // The face a and b share holds v, current and the vertex of a that is not opposite b.
      const int opposite = a->index(b);
      for (int j = 0; j < 4; ++j) {
        const Vertex_handle w = a->vertex(j);
        if (j == opposite || w == v || w == current || w == previous) continue;
        next = w;
        next_cell = a;
      }
    } while (++circ != done);
    if (changes != 2 || next == Vertex_handle()) return false;
    previous = current;
    current = next;
    cell = next_cell;
    if (++length > num_edges) return false;
  }
  return length == num_edges;
}

}  // namespace ms::manifold_detail
