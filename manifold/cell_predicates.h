// Stateless exact predicates on one cell of the triangulation and a segment a -> b (a viewing
// ray: camera -> point): which faces the end points are beyond, whether the open segment meets
// the open cell, through which face it leaves. Every decision is a CGAL orientation test (exact);
// docs/design/manifold.md derives them. Internal to manifold/.
//
// Inline: the ray walks (ray_walker.h) call them in every step, and they stay inlined into the
// walks' inner loops as they were when everything sat in one file.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <utility>
#include <vector>

#include "manifold/triangulation.h"

namespace ms::manifold_detail {

// Sign of K_ij = A_j B_i - A_i B_j is kPluckerSign[i][j] * orientation(p_k, p_l, a, b) for a
// positively oriented cell, where {k < l} are the two other indices (a Grassmann-Pluecker
// identity; A_i, B_i are the orientations of a and b against face i).
inline constexpr int kPluckerSign[4][4] = {
    {0, -1, 1, -1}, {1, 0, -1, 1}, {-1, 1, 0, -1}, {1, -1, 1, 0}};

// Fast walk step: entering a cell through face e, the segment leaves through the face given
// by the signs of orientation(p_e, p_m, a, b) for the three other vertices m (in increasing
// order), coded as 4*(s1>0) + 2*(s2>0) + (s3>0). Codes 0 and 7 cannot occur; a zero sign is a
// degenerate step handled by the general rule. (Derived and checked numerically.)
inline constexpr int kExitFace[4][8] = {{-1, 1, 3, 3, 2, 1, 2, -1},
                                        {-1, 2, 0, 2, 3, 3, 0, -1},
                                        {-1, 0, 3, 3, 1, 0, 1, -1},
                                        {-1, 1, 0, 1, 2, 2, 0, -1}};

// The two indices of {0, 1, 2, 3} other than i and j, in increasing order.
inline void OtherTwo(int i, int j, int* k, int* l) {
  int found[2], n = 0;
  for (int m = 0; m < 4; ++m) {
    if (m != i && m != j) found[n++] = m;
  }
  *k = found[0];
  *l = found[1];
}

// Fast walk step: the face through which the segment a -> b leaves cell c, having entered it
// through face `entry`, from three orientations (kExitFace); -1 where one is zero (a
// degenerate step, for the general rule).
inline int FastExitFace(const Cell_handle& c, int entry, const Point& a, const Point& b) {
  const Point& apex = c->vertex(entry)->point();
  int code = 0;
  for (int m = 0; m < 4; ++m) {
    if (m == entry) continue;
    const CGAL::Orientation o = CGAL::orientation(apex, c->vertex(m)->point(), a, b);
    if (o == CGAL::COPLANAR) return -1;
    code = 2 * code + (o == CGAL::POSITIVE);
  }
  return kExitFace[entry][code];
}

// Orientations of the segment end points against the four faces of a finite cell.
struct FaceSides {
  int a[4];  // sign of orientation with vertex i replaced by a (> 0: a on the inner side)
  int b[4];
};

inline FaceSides ComputeFaceSides(const Cell_handle& c, const Point& a, const Point& b) {
  const Point& p0 = c->vertex(0)->point();
  const Point& p1 = c->vertex(1)->point();
  const Point& p2 = c->vertex(2)->point();
  const Point& p3 = c->vertex(3)->point();
  FaceSides s;
  // An end point that is a vertex of c lies on the three faces through it and on the cell's
  // side of the fourth: answered directly (the exact predicate would need multi-precision).
  const auto sides = [&](const Point& x, int* out) {
    for (int i = 0; i < 4; ++i) {
      if (&c->vertex(i)->point() == &x) {
        for (int j = 0; j < 4; ++j) out[j] = j == i ? 1 : 0;
        return;
      }
    }
    out[0] = CGAL::orientation(x, p1, p2, p3);
    out[1] = CGAL::orientation(p0, x, p2, p3);
    out[2] = CGAL::orientation(p0, p1, x, p3);
    out[3] = CGAL::orientation(p0, p1, p2, x);
  };
  sides(a, s.a);
  sides(b, s.b);
  return s;
}

// Orientation of point x against face i of a finite cell (> 0: on the cell's side).
inline CGAL::Orientation FaceSide(const Cell_handle& c, int i, const Point& x) {
  const Point* p[4] = {&c->vertex(0)->point(), &c->vertex(1)->point(), &c->vertex(2)->point(),
                       &c->vertex(3)->point()};
  p[i] = &x;
  return CGAL::orientation(*p[0], *p[1], *p[2], *p[3]);
}

// The cell a ray from `camera` enters past its end point, the vertex v: of the finite cells in
// `star` (v's), the one whose corner at v holds the ray's direction, i.e. that holds
// v + (v - camera) on its side of each of its faces through v. The first in `star`'s order that
// holds it strictly, else the first that holds it on a face; a default handle if none does.
inline Cell_handle CellBehind(const Vertex_handle& v, const Point& camera,
                              const std::vector<Cell_handle>& star) {
  const Point& p = v->point();
  const Point beyond(2 * p.x() - camera.x(), 2 * p.y() - camera.y(), 2 * p.z() - camera.z());
  Cell_handle on_face;
  for (const Cell_handle& c : star) {
    const int i = c->index(v);
    bool strict = true, holds = true;
    for (int j = 0; j < 4 && holds; ++j) {
      if (j == i) continue;
      const CGAL::Orientation side = FaceSide(c, j, beyond);
      holds = side != CGAL::NEGATIVE;
      strict &= side == CGAL::POSITIVE;
    }
    if (holds && strict) return c;
    if (holds && on_face == Cell_handle()) on_face = c;
  }
  return on_face;
}

// Sign of K_ij (see kPluckerSign).
inline int PluckerSign(const Cell_handle& c, int i, int j, const Point& a, const Point& b) {
  int k, l;
  OtherTwo(i, j, &k, &l);
  return kPluckerSign[i][j] *
         static_cast<int>(CGAL::orientation(c->vertex(k)->point(), c->vertex(l)->point(), a, b));
}

// Exact test: does the open segment (a, b) meet the open (finite) cell? Along the segment,
// face i's orientation is (1-t) A_i + t B_i; the segment is inside for the t where all four
// are positive: an interval bounded below by faces with A <= 0 < B and above by faces with
// A > 0 >= B. It is non-empty iff every lower bound is below every upper bound.
inline bool SegmentCrossesCell(const Cell_handle& c, const Point& a, const Point& b,
                               const FaceSides& s) {
  int lower[4], upper[4], nl = 0, nu = 0;
  for (int i = 0; i < 4; ++i) {
    if (s.a[i] <= 0 && s.b[i] <= 0) return false;
    if (s.a[i] <= 0) {
      lower[nl++] = i;
    } else if (s.b[i] <= 0) {
      upper[nu++] = i;
    }
  }
  for (int x = 0; x < nl; ++x) {
    for (int y = 0; y < nu; ++y) {
      if (PluckerSign(c, lower[x], upper[y], a, b) <= 0) return false;
    }
  }
  return true;
}

inline bool SegmentCrossesCell(const Cell_handle& c, const Point& a, const Point& b) {
  return SegmentCrossesCell(c, a, b, ComputeFaceSides(c, a, b));
}

// The faces of a crossed cell with the camera beyond them (`camera_sides`: the camera's row of
// FaceSides): a ray from that camera spreads w2 across them (the walks' visit mask).
inline unsigned CameraSideMask(const int camera_sides[4]) {
  unsigned mask = 0;
  for (int i = 0; i < 4; ++i) mask |= (camera_sides[i] < 0 ? 1u : 0u) << i;
  return mask;
}

// The face through which the open segment a -> b leaves the crossed cell c (s: its sides from
// ComputeFaceSides(c, a, b)): among the faces with a inside and b beyond or on, the one whose
// bound on the segment's parameter comes first; -1 if none. ties[0, *num_ties) are the faces
// tying for it: two mean leaving through an edge, three through a vertex.
inline int ExitFace(const Cell_handle& c, const Point& a, const Point& b, const FaceSides& s,
                    int ties[3], int* num_ties) {
  int exit = -1;
  *num_ties = 0;
  for (int j = 0; j < 4; ++j) {
    if (!(s.a[j] > 0 && s.b[j] <= 0)) continue;
    if (exit < 0) {
      exit = j;
      ties[0] = j;
      *num_ties = 1;
      continue;
    }
    // U_j < U_exit  <=>  K_{j,exit} < 0.
    const int order = PluckerSign(c, j, exit, a, b);
    if (order < 0) {
      exit = j;
      ties[0] = j;
      *num_ties = 1;
    } else if (order == 0) {
      ties[(*num_ties)++] = j;
    }
  }
  return exit;
}

// Does the closed segment [a, b] meet the closed box [lo, hi]? (slab clipping)
// *entry receives the parameter (0 at a, 1 at b) where it enters the box.
inline bool SegmentMeetsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double* entry) {
  double t0 = 0, t1 = 1;
  for (int axis = 0; axis < 3; ++axis) {
    const double d = b[axis] - a[axis];
    if (d == 0) {
      if (a[axis] < lo[axis] || a[axis] > hi[axis]) return false;
      continue;
    }
    double near = (lo[axis] - a[axis]) / d, far = (hi[axis] - a[axis]) / d;
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return false;
  }
  *entry = t0;
  return true;
}

}  // namespace ms::manifold_detail
