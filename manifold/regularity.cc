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
  std::vector<std::pair<Vertex_handle, Vertex_handle>>& link = link_;
  link.clear();
  for (const Cell_handle& c : around) {
    if (!label(c)) continue;
    for (int i = 0; i < 4; ++i) {
      if (c->vertex(i) == v || label(c->neighbor(i))) continue;
      Vertex_handle ends[2];
      int n = 0;
      for (int j = 0; j < 4; ++j) {
        if (j != i && c->vertex(j) != v) ends[n++] = c->vertex(j);
      }
      link.emplace_back(ends[0], ends[1]);
    }
  }
  if (link.empty()) return true;
  // Every link vertex must have degree 2 and the edges must form a single cycle.
  std::vector<std::pair<Vertex_handle, int>>& degree = degree_;
  degree.clear();
  for (const auto& [p, q] : link) {
    for (const Vertex_handle& w : {p, q}) {
      auto it = std::find_if(degree.begin(), degree.end(),
                             [&](const auto& entry) { return entry.first == w; });
      if (it == degree.end()) {
        degree.emplace_back(w, 1);
      } else if (++it->second > 2) {
        return false;
      }
    }
  }
  for (const auto& entry : degree) {
    if (entry.second != 2) return false;
  }
  // Walk the cycle from the first edge; it must use every edge.
  const Vertex_handle first = link[0].first;
  Vertex_handle previous = first, current = link[0].second;
  size_t length = 1;
  while (current != first) {
    bool advanced = false;
    for (const auto& [p, q] : link) {
      const Vertex_handle other = p == current ? q : q == current ? p : Vertex_handle();
      if (other != Vertex_handle() && other != previous) {
        previous = current;
        current = other;
        advanced = true;
        break;
      }
    }
    if (!advanced) return false;
    if (++length > link.size()) return false;
  }
  return length == link.size();
}

}  // namespace ms::manifold_detail
