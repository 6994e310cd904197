#include "mesh/float_robustness.h"

// CGAL only for its box intersection (candidate pairs); every predicate here is in double.
#include <CGAL/box_intersection_d.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "base/check.h"
#include "base/error.h"
#include "base/log.h"
#include "base/parallel_for.h"

namespace ms {
namespace float_robustness_internal {
namespace {

using Eigen::Vector3d;

// ----- Möller's triangle-triangle test, as Open3D runs it. ----------------------------------
// Written out on plain arrays, component by component, so that every sum is evaluated in the
// same order as in the reference implementation (Eigen's dot products may reorder them).

constexpr double kMollerEpsilon = 1e-6;  // plane distances below this are taken as 0

using P3 = std::array<double, 3>;

P3 Sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
P3 Cross(const P3& a, const P3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Dot(const P3& a, const P3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Edge (v0, v1) against the three edges of u, projected on the axes (i0, i1) (Franklin
// Antonio's segment intersection test, Graphics Gems III).
bool EdgeAgainstTriangleEdges(const P3& v0, const P3& v1, const std::array<P3, 3>& u, int i0,
                              int i1) {
  const double ax = v1[i0] - v0[i0];
  const double ay = v1[i1] - v0[i1];
  for (int k = 0; k < 3; ++k) {
    const P3& u0 = u[k];
    const P3& u1 = u[(k + 1) % 3];
    const double bx = u0[i0] - u1[i0];
    const double by = u0[i1] - u1[i1];
    const double cx = v0[i0] - u0[i0];
    const double cy = v0[i1] - u0[i1];
    const double f = ay * bx - ax * by;
    const double d = by * cx - bx * cy;
    if ((f > 0 && d >= 0 && d <= f) || (f < 0 && d <= 0 && d >= f)) {
      const double e = ax * cy - ay * cx;
      if (f > 0) {
        if (e >= 0 && e <= f) return true;
      } else {
        if (e <= 0 && e >= f) return true;
      }
    }
  }
  return false;
}

// Strictly inside on the same side of all three edges of u (projected on (i0, i1)).
bool PointInTriangle(const P3& p, const std::array<P3, 3>& u, int i0, int i1) {
  double d[3];
  for (int k = 0; k < 3; ++k) {
    const P3& a = u[k];
    const P3& b = u[(k + 1) % 3];
    const double la = b[i1] - a[i1];
    const double lb = -(b[i0] - a[i0]);
    const double lc = -la * a[i0] - lb * a[i1];
    d[k] = la * p[i0] + lb * p[i1] + lc;
  }
  return d[0] * d[1] > 0.0 && d[0] * d[2] > 0.0;
}

bool CoplanarTrianglesIntersect(const P3& n, const std::array<P3, 3>& v,
                                const std::array<P3, 3>& u) {
  // Project on the axis-aligned plane where the triangles are largest.
  const double a0 = std::fabs(n[0]), a1 = std::fabs(n[1]), a2 = std::fabs(n[2]);
  int i0, i1;
  if (a0 > a1) {
    if (a0 > a2) {
      i0 = 1;
      i1 = 2;
    } else {
      i0 = 0;
      i1 = 1;
    }
  } else {
    if (a2 > a1) {
      i0 = 0;
      i1 = 1;
    } else {
      i0 = 0;
      i1 = 2;
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (EdgeAgainstTriangleEdges(v[k], v[(k + 1) % 3], u, i0, i1)) return true;
  }
  return PointInTriangle(v[0], u, i0, i1) || PointInTriangle(u[0], v, i0, i1);
}

// The interval where the other triangle's plane cuts this triangle, on the intersection line,
// scaled so that no division is needed: [a + b / x0, a + c / x1]. False when the triangle lies
// in the plane (all three distances are 0).
struct Interval {
  double a, b, c, x0, x1;
};
bool ComputeInterval(const double vp[3], const double d[3], double d0d1, double d0d2,
                     Interval* out) {
  // The vertex alone on its side of the plane is the apex k; (i, j) the other two.
  int k;
  if (d0d1 > 0.0) {
    k = 2;  // d0, d1 on the same side, d2 on the other or on the plane
  } else if (d0d2 > 0.0) {
    k = 1;
  } else if (d[1] * d[2] > 0.0 || d[0] != 0.0) {
    k = 0;
  } else if (d[1] != 0.0) {
    k = 1;
  } else if (d[2] != 0.0) {
    k = 2;
  } else {
    return false;
  }
  const int i = k == 0 ? 1 : 0;
  const int j = k == 2 ? 1 : 2;
  out->a = vp[k];
  out->b = (vp[i] - vp[k]) * d[k];
  out->c = (vp[j] - vp[k]) * d[k];
  out->x0 = d[k] - d[i];
  out->x1 = d[k] - d[j];
  return true;
}

bool MollerNoDivision(const std::array<P3, 3>& v, const std::array<P3, 3>& u) {
  // Plane of v; signed (unnormalised) distances of u's vertices to it.
  const P3 n1 = Cross(Sub(v[1], v[0]), Sub(v[2], v[0]));
  const double d1 = -Dot(n1, v[0]);
  double du[3];
  for (int k = 0; k < 3; ++k) {
    du[k] = Dot(n1, u[k]) + d1;
    if (std::fabs(du[k]) < kMollerEpsilon) du[k] = 0.0;
  }
  const double du0du1 = du[0] * du[1];
  const double du0du2 = du[0] * du[2];
  if (du0du1 > 0.0 && du0du2 > 0.0) return false;  // u entirely on one side

  const P3 n2 = Cross(Sub(u[1], u[0]), Sub(u[2], u[0]));
  const double d2 = -Dot(n2, u[0]);
  double dv[3];
  for (int k = 0; k < 3; ++k) {
    dv[k] = Dot(n2, v[k]) + d2;
    if (std::fabs(dv[k]) < kMollerEpsilon) dv[k] = 0.0;
  }
  const double dv0dv1 = dv[0] * dv[1];
  const double dv0dv2 = dv[0] * dv[2];
  if (dv0dv1 > 0.0 && dv0dv2 > 0.0) return false;

  // Project on the largest component of the intersection line's direction.
  const P3 dir = Cross(n1, n2);
  double max = std::fabs(dir[0]);
  int index = 0;
  const double bb = std::fabs(dir[1]);
  const double cc = std::fabs(dir[2]);
  if (bb > max) max = bb, index = 1;
  if (cc > max) index = 2;
  const double vp[3] = {v[0][index], v[1][index], v[2][index]};
  const double up[3] = {u[0][index], u[1][index], u[2][index]};

  Interval iv, iu;
  if (!ComputeInterval(vp, dv, dv0dv1, dv0dv2, &iv)) return CoplanarTrianglesIntersect(n1, v, u);
  if (!ComputeInterval(up, du, du0du1, du0du2, &iu)) return CoplanarTrianglesIntersect(n1, v, u);

  const double xx = iv.x0 * iv.x1;
  const double yy = iu.x0 * iu.x1;
  const double xxyy = xx * yy;
  double tmp = iv.a * xxyy;
  double s1[2] = {tmp + iv.b * iv.x1 * yy, tmp + iv.c * iv.x0 * yy};
  tmp = iu.a * xxyy;
  double s2[2] = {tmp + iu.b * xx * iu.x1, tmp + iu.c * xx * iu.x0};
  if (s1[0] > s1[1]) std::swap(s1[0], s1[1]);
  if (s2[0] > s2[1]) std::swap(s2[0], s2[1]);
  return !(s1[1] < s2[0] || s2[1] < s1[0]);
}

P3 ToP3(const Vector3d& x) { return {x[0], x[1], x[2]}; }

// ----- Distances. ----------------------------------------------------------------------------

// (b - a) x (c - a) . (d - a): positive when d is on the side of abc's normal.
double Orient(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a);
}

double PointSegmentDistance2(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

double PointTriangleDistance2(const Vector3d& p, const Triangle& t) {
  const Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  const double n2 = n.squaredNorm();
  if (n2 > 0) {
    // Inside the prism over the triangle: the distance is the one to the plane.
    const double s0 = (t[1] - t[0]).cross(p - t[0]).dot(n);
    const double s1 = (t[2] - t[1]).cross(p - t[1]).dot(n);
    const double s2 = (t[0] - t[2]).cross(p - t[2]).dot(n);
    if (s0 >= 0 && s1 >= 0 && s2 >= 0) {
      const double h = (p - t[0]).dot(n);
      return h * h / n2;
    }
  }
  return std::min({PointSegmentDistance2(p, t[0], t[1]), PointSegmentDistance2(p, t[1], t[2]),
                   PointSegmentDistance2(p, t[2], t[0])});
}

// Closest points of segments p0p1 and q0q1 (Ericson, Real-Time Collision Detection, 5.1.9),
// degenerate segments included.
double SegmentSegmentDistance2(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0,
                               const Vector3d& q1) {
  const Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return r.squaredNorm();
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return (p0 + s * d1 - (q0 + t * d2)).squaredNorm();
}

}  // namespace

bool TrianglesIntersectLikeOpen3d(const Triangle& p, const Triangle& q) {
  // Open3D's preconditioning: the six points to zero mean and unit spread on each axis.
  const Vector3d mu = (p[0] + p[1] + p[2] + q[0] + q[1] + q[2]) / 6;
  const Vector3d sigma = (((p[0] - mu).array().square() + (p[1] - mu).array().square() +
                           (p[2] - mu).array().square() + (q[0] - mu).array().square() +
                           (q[1] - mu).array().square() + (q[2] - mu).array().square()) /
                          5)
                             .sqrt() +
                         1e-12;
  auto scaled = [&](const Vector3d& x) {
    const Vector3d y = (x - mu).array() / sigma.array();
    return ToP3(y);
  };
  return MollerNoDivision({scaled(p[0]), scaled(p[1]), scaled(p[2])},
                          {scaled(q[0]), scaled(q[1]), scaled(q[2])});
}

bool SegmentCrossesTriangle(const Vector3d& a, const Vector3d& b, const Triangle& t) {
  const double sa = Orient(t[0], t[1], t[2], a);
  const double sb = Orient(t[0], t[1], t[2], b);
  if ((sa > 0 && sb > 0) || (sa < 0 && sb < 0) || (sa == 0 && sb == 0)) return false;
  const double s0 = Orient(a, b, t[0], t[1]);
  const double s1 = Orient(a, b, t[1], t[2]);
  const double s2 = Orient(a, b, t[2], t[0]);
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

bool TrianglesSurelyApart(const Triangle& p, const Triangle& q, double distance) {
  Vector3d lo = p[0], hi = p[0];
  for (const Triangle* t : {&p, &q}) {
    for (const Vector3d& x : *t) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
  }
  const double margin =
      1e-9 * (hi - lo).norm() + 1e-12 * hi.cwiseAbs().cwiseMax(lo.cwiseAbs()).sum();
  const auto apart_along = [&](Vector3d axis) {
    const double length = axis.norm();
    if (!(length > 0)) return false;
    axis /= length;
    const double p0 = axis.dot(p[0]), p1 = axis.dot(p[1]), p2 = axis.dot(p[2]);
    const double q0 = axis.dot(q[0]), q1 = axis.dot(q[1]), q2 = axis.dot(q[2]);
    const double gap = std::max(std::min({q0, q1, q2}) - std::max({p0, p1, p2}),
                                std::min({p0, p1, p2}) - std::max({q0, q1, q2}));
    return gap > distance + margin;
  };
  const Vector3d np = (p[1] - p[0]).cross(p[2] - p[0]), nq = (q[1] - q[0]).cross(q[2] - q[0]);
  if (apart_along(np) || apart_along(nq)) return true;
  for (int i = 0; i < 3; ++i) {
    if (apart_along(np.cross(p[(i + 1) % 3] - p[i])) ||
        apart_along(nq.cross(q[(i + 1) % 3] - q[i]))) {
      return true;
    }
  }
  return false;
}

namespace {

// SegmentCrossesTriangle, confirmed: the point where ab meets t's plane lies on t (within a
// rounding's reach). Nearly in t's plane, the orientations that test finds crossing are rounding
// noise; an edge that does not meet t there is left to the distances.
bool SegmentMeetsTriangle(const Vector3d& a, const Vector3d& b, const Triangle& t) {
  if (!SegmentCrossesTriangle(a, b, t)) return false;
  const double sa = Orient(t[0], t[1], t[2], a), sb = Orient(t[0], t[1], t[2], b);
  const Vector3d x = sa == sb ? a : Vector3d(a + sa / (sa - sb) * (b - a));
  const double size = (b - a).norm() + (t[1] - t[0]).norm() + (t[2] - t[1]).norm();
  const double reach = 1e-9 * size;
  return PointTriangleDistance2(x, t) <= reach * reach;
}

}  // namespace

double TriangleDistance(const Triangle& p, const Triangle& q) {
  for (int i = 0; i < 3; ++i) {
    if (SegmentMeetsTriangle(p[i], p[(i + 1) % 3], q)) return 0;
    if (SegmentMeetsTriangle(q[i], q[(i + 1) % 3], p)) return 0;
  }
  double d2 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    d2 = std::min({d2, PointTriangleDistance2(p[i], q), PointTriangleDistance2(q[i], p)});
    for (int j = 0; j < 3; ++j) {
      d2 = std::min(d2, SegmentSegmentDistance2(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3]));
    }
  }
  return std::sqrt(d2);
}

namespace {

Eigen::Vector3d ClosestOnSegment(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                                 const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double l2 = ab.squaredNorm();
  return l2 > 0 ? Eigen::Vector3d(a + std::clamp((x - a).dot(ab) / l2, 0.0, 1.0) * ab) : a;
}

// The closest points of segments p0p1 and q0q1 (SegmentSegmentDistance2's parameters).
std::array<Eigen::Vector3d, 2> SegmentClosestPoints(const Eigen::Vector3d& p0,
                                                    const Eigen::Vector3d& p1,
                                                    const Eigen::Vector3d& q0,
                                                    const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a > 0 && e > 0) {
    const double b = d1.dot(d2), c = d1.dot(r), denom = a * e - b * b;
    s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
    t = (b * s + f) / e;
    if (t < 0 || t > 1) {
      t = std::clamp(t, 0.0, 1.0);
      s = std::clamp((b * t - c) / a, 0.0, 1.0);
    }
  } else if (a > 0) {
    s = std::clamp(-d1.dot(r) / a, 0.0, 1.0);
  } else if (e > 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  }
  return {p0 + s * d1, q0 + t * d2};
}

}  // namespace

std::array<Eigen::Vector3d, 2> TriangleClosestPoints(const Triangle& p, const Triangle& q) {
  std::array<Eigen::Vector3d, 2> best = {p[0], q[0]};
  double best2 = std::numeric_limits<double>::infinity();
  const auto consider = [&](const Eigen::Vector3d& on_p, const Eigen::Vector3d& on_q) {
    const double d2 = (on_p - on_q).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best = {on_p, on_q};
    }
  };
  for (int i = 0; i < 3; ++i) {
    consider(p[i], ClosestPointOnTriangle(p[i], q));
    consider(ClosestPointOnTriangle(q[i], p), q[i]);
    for (int j = 0; j < 3; ++j) {
      const auto c = SegmentClosestPoints(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3]);
      consider(c[0], c[1]);
    }
  }
  return best;
}

}  // namespace float_robustness_internal

bool PointOverTriangle(const Eigen::Vector3d& x, const std::array<Eigen::Vector3d, 3>& t) {
  const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  return n.squaredNorm() > 0 && (t[1] - t[0]).cross(x - t[0]).dot(n) >= 0 &&
         (t[2] - t[1]).cross(x - t[1]).dot(n) >= 0 && (t[0] - t[2]).cross(x - t[2]).dot(n) >= 0;
}

Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& x,
                                       const std::array<Eigen::Vector3d, 3>& t) {
  if (PointOverTriangle(x, t)) {
    const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
    return x - (x - t[0]).dot(n) / n.squaredNorm() * n;
  }
  Eigen::Vector3d best = t[0];
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d c = float_robustness_internal::ClosestOnSegment(x, t[i], t[(i + 1) % 3]);
    if ((c - x).squaredNorm() < (best - x).squaredNorm()) best = c;
  }
  return best;
}

namespace {

using float_robustness_internal::Triangle;

struct StopSearch {};

template <typename T>
void AddExamples(const std::vector<T>& sorted, int max_examples, std::vector<T>* examples) {
  const size_t n = std::min(sorted.size(), static_cast<size_t>(std::max(max_examples, 0)));
  examples->assign(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n));
}

// Edges and angles of the faces with three distinct indices.
void MeasureFaces(const Mesh& mesh, const std::vector<uint8_t>& usable,
                  const std::vector<uint8_t>& focus, FloatRobustnessReport* r) {
  double shortest = std::numeric_limits<double>::infinity();
  double smallest = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    if (!usable[f] || (!focus.empty() && !focus[f]) || t[0] == t[1] || t[1] == t[2] ||
        t[0] == t[2]) {
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const int32_t a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      const Eigen::Vector3d ab = mesh.vertices[b] - mesh.vertices[a];
      const Eigen::Vector3d ac = mesh.vertices[c] - mesh.vertices[a];
      const double length = ab.norm();
      if (length < shortest || !r->shortest_edge) {
        shortest = length;
        r->shortest_edge = length;
        r->shortest_edge_vertices = {std::min(a, b), std::max(a, b)};
        r->shortest_edge_face = static_cast<int64_t>(f);
      }
      // atan2 of |sin| and cos: accurate for tiny angles, where acos is not.
      const double angle = std::atan2(ab.cross(ac).norm(), ab.dot(ac)) * (180.0 / M_PI);
      if (angle < smallest || !r->smallest_angle_degrees) {
        smallest = angle;
        r->smallest_angle_degrees = angle;
        r->smallest_angle_face = static_cast<int64_t>(f);
        r->smallest_angle_vertex = a;
      }
    }
  }
}

// A box for CGAL's box search in floats, rounded outward from the double box it stands for:
// 28 bytes against 64 for a double box with an id and an index. It finds a superset of the
// double boxes' pairs; the exact tests after it decide.
class SearchBox {
 public:
  using NT = float;
  using ID = std::size_t;
  SearchBox() = default;
  SearchBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int64_t index)
      : index_(static_cast<uint32_t>(index)) {
    MS_CHECK(index >= 0 && index <= UINT32_MAX) << "box index " << index;
    for (int d = 0; d < 3; ++d) {
      lo_[d] = float_robustness_internal::FloatAtOrBelow(lo[d]);
      hi_[d] = float_robustness_internal::FloatAtOrAbove(hi[d]);
    }
  }
  static int dimension() { return 3; }
  float min_coord(int d) const { return lo_[d]; }
  float max_coord(int d) const { return hi_[d]; }
  ID id() const { return index_; }
  int64_t info() const { return index_; }

 private:
  float lo_[3] = {}, hi_[3] = {};
  uint32_t index_ = 0;
};

// Calls callback(x, y) for every pair of intersecting boxes among make_box(i, &box) for i in
// [0, count) (false: no box for i), or with `focus` (flags indexed by the boxes' info) only for
// pairs with a flagged box; a pair of two flagged boxes may come twice (callers deduplicate).
//
// The search runs slab by slab along x (about boxes_per_slab boxes each), each slab with only
// the boxes that reach into it: CGAL copies the boxes it is given (box_self_intersection_d),
// and at 2·10^6 faces two copies of all of them were the float check's peak of memory, and the
// coordinator's with it. A pair is reported by the slab that holds the larger of its two boxes'
// lower x (both boxes reach into it), so once, as by one search over all the boxes.
template <typename MakeBox, typename Callback>
void ForIntersectingBoxes(int64_t count, MakeBox&& make_box, const std::vector<uint8_t>& focus,
                          int64_t boxes_per_slab, Callback&& callback) {
  using Box = SearchBox;
  // The slabs' bounds: quantiles of the boxes' lower x.
  std::vector<float> bounds;
  {
    std::vector<float> lower;
    Box box;
    for (int64_t i = 0; i < count; ++i) {
      if (make_box(i, &box)) lower.push_back(box.min_coord(0));
    }
    const int64_t n = static_cast<int64_t>(lower.size());
    const int64_t slabs = std::max<int64_t>(1, n / boxes_per_slab);
    for (int64_t k = 1; k < slabs; ++k) {
      auto at = lower.begin() + k * n / slabs;
      std::nth_element(lower.begin(), at, lower.end());
      bounds.push_back(*at);
    }
    std::sort(bounds.begin(), bounds.end());
    bounds.erase(std::unique(bounds.begin(), bounds.end()), bounds.end());
  }
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<Box> boxes, flagged;
  for (size_t k = 0; k <= bounds.size(); ++k) {
    const float from = k == 0 ? -inf : bounds[k - 1];
    const float to = k == bounds.size() ? inf : bounds[k];
    boxes.clear();
    flagged.clear();
    Box box;
    for (int64_t i = 0; i < count; ++i) {
      if (!make_box(i, &box) || box.max_coord(0) < from || box.min_coord(0) >= to) continue;
      boxes.push_back(box);
      if (!focus.empty() && focus[box.info()]) flagged.push_back(box);
    }
    const auto in_slab = [&](const Box& x, const Box& y) {
      const float lower = std::max(x.min_coord(0), y.min_coord(0));
      return lower >= from && lower < to;
    };
    if (focus.empty()) {
      CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& x, const Box& y) {
        if (in_slab(x, y)) callback(x, y);
      });
    } else {
      CGAL::box_intersection_d(flagged.begin(), flagged.end(), boxes.begin(), boxes.end(),
                               [&](const Box& x, const Box& y) {
                                 if (x.info() != y.info() && in_slab(x, y)) callback(x, y);
                               });
    }
  }
}

// One flag per vertex: set for the vertices of the faces flagged in `focus_faces` (empty when
// that is empty: no focus).
std::vector<uint8_t> VerticesOfFlaggedFaces(const Mesh& mesh,
                                            const std::vector<uint8_t>& focus_faces) {
  std::vector<uint8_t> flagged;
  if (focus_faces.empty()) return flagged;
  flagged.assign(mesh.vertices.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!focus_faces[f]) continue;
    for (int32_t v : mesh.faces[f]) {
      if (v >= 0 && static_cast<size_t>(v) < flagged.size()) flagged[v] = 1;
    }
  }
  return flagged;
}

// The pairs of `candidates` that ForIntersectingBoxes would hand `callback` (with a flagged box
// when `focus` is set, boxes that meet as CGAL's closed boxes do), in list order.
template <typename MakeBox, typename Callback>
void ForCandidatePairs(const std::vector<std::array<int32_t, 2>>& candidates, MakeBox&& make_box,
                       const std::vector<uint8_t>& focus, Callback&& callback) {
  SearchBox x, y;
  for (const auto& [a, b] : candidates) {
    if (!focus.empty() && !focus[a] && !focus[b]) continue;
    if (!make_box(a, &x) || !make_box(b, &y)) continue;
    bool meet = true;
    for (int d = 0; d < 3 && meet; ++d) {
      meet = x.min_coord(d) <= y.max_coord(d) && y.min_coord(d) <= x.max_coord(d);
    }
    if (meet) callback(x, y);
  }
}

void FindNearVertices(const Mesh& mesh, const std::vector<uint8_t>& referenced,
                      const FloatRobustnessOptions& options, FloatRobustnessReport* r) {
  using Box = SearchBox;
  const double tol = r->tolerance;
  const Eigen::Vector3d slack = Eigen::Vector3d::Constant(tol);
  // Boxes a whole tolerance wide on each side: no pair within the tolerance is lost to
  // rounding; the distance below decides.
  const auto make_box = [&](int64_t v, Box* box) {
    if (!referenced[v]) return false;
    const Eigen::Vector3d& p = mesh.vertices[v];
    *box = Box(p - slack, p + slack, v);
    return true;
  };
  std::vector<std::pair<std::array<int32_t, 2>, double>> found;
  auto callback = [&](const Box& x, const Box& y) {
    const auto a = static_cast<int32_t>(std::min(x.info(), y.info()));
    const auto b = static_cast<int32_t>(std::max(x.info(), y.info()));
    const double d = (mesh.vertices[a] - mesh.vertices[b]).norm();
    if (d > tol) return;
    found.push_back({{a, b}, d});
    if (static_cast<int64_t>(found.size()) >= options.max_pairs) throw StopSearch{};
  };
  const std::vector<uint8_t> focus = VerticesOfFlaggedFaces(mesh, options.focus_faces);
  try {
    if (options.candidates) {
      ForCandidatePairs(options.candidates->vertices, make_box, focus, callback);
    } else {
      ForIntersectingBoxes(static_cast<int64_t>(mesh.vertices.size()), make_box, focus,
                           options.boxes_per_slab, callback);
    }
  } catch (const StopSearch&) {
    r->near_vertex_pairs_truncated = true;
  }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  r->num_near_vertex_pairs = static_cast<int64_t>(found.size());
  std::vector<std::array<int32_t, 2>> pairs;
  for (const auto& [pair, d] : found) {
    pairs.push_back(pair);
    r->closest_vertex_distance = std::min(r->closest_vertex_distance.value_or(d), d);
  }
  AddExamples(pairs, options.max_examples, &r->near_vertex_examples);
}

void FindCloseFacePairs(const Mesh& mesh, const std::vector<uint8_t>& usable,
                        const FloatRobustnessOptions& options, FloatRobustnessReport* r) {
  using Box = SearchBox;
  const double tol = r->tolerance;
  const auto nf = static_cast<int64_t>(mesh.faces.size());
  // The faces' own boxes (Open3D's pre-test: closed, not enlarged), computed where needed
  // rather than stored (48 bytes a face at the cleanup's peak of memory), and the enlarged ones.
  const auto box_of = [&](int64_t f, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3d &p0 = mesh.vertices[t[0]], &p1 = mesh.vertices[t[1]],
                          &p2 = mesh.vertices[t[2]];
    *lo = p0.array().min(p1.array().min(p2.array()));
    *hi = p0.array().max(p1.array().max(p2.array()));
  };
  const auto make_box = [&](int64_t f, Box* box) {
    if (!usable[f]) return false;
    Eigen::Vector3d lo, hi;
    box_of(f, &lo, &hi);
    *box = Box(lo.array() - tol, hi.array() + tol, f);
    return true;
  };
  const Timer timer;
  int64_t tested = 0;
  std::vector<std::pair<std::array<int64_t, 2>, double>> close;
  std::vector<std::array<int64_t, 2>> crossing;
  bool close_full = false, crossing_full = false;
  auto triangle = [&](int64_t f) {
    const auto& t = mesh.faces[f];
    return Triangle{mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]};
  };
  // The pairs the box search finds are tested a batch at a time on all cores, then taken in
  // the order they were found: the same lists, cut at the same pair, as one pair at a time.
  struct Candidate {
    int64_t f, g;
    double distance;
    bool crosses;
  };
  std::vector<Candidate> batch;
  constexpr size_t kBatch = 1 << 15, kPerTask = 256;
  const auto test_batch = [&] {
    ParallelFor((batch.size() + kPerTask - 1) / kPerTask, [&](size_t task) {
      const size_t end = std::min(batch.size(), (task + 1) * kPerTask);
      for (size_t i = task * kPerTask; i < end; ++i) {
        Candidate& c = batch[i];
        const Triangle p = triangle(c.f), q = triangle(c.g);
        Eigen::Vector3d lo_f, hi_f, lo_g, hi_g;
        box_of(c.f, &lo_f, &hi_f);
        box_of(c.g, &lo_g, &hi_g);
        c.crosses = (hi_f.array() >= lo_g.array()).all() && (hi_g.array() >= lo_f.array()).all() &&
                    float_robustness_internal::TrianglesIntersectLikeOpen3d(p, q);
        c.distance = float_robustness_internal::TrianglesSurelyApart(p, q, tol)
                         ? std::numeric_limits<double>::infinity()
                         : float_robustness_internal::TriangleDistance(p, q);
      }
    });
    for (const Candidate& c : batch) {
      ++tested;
      if (!crossing_full && c.crosses) {
        crossing.push_back({c.f, c.g});
        crossing_full = static_cast<int64_t>(crossing.size()) >= options.max_pairs;
      }
      if (!close_full && c.distance <= tol) {
        close.push_back({{c.f, c.g}, c.distance});
        close_full = static_cast<int64_t>(close.size()) >= options.max_pairs;
      }
      if (close_full && crossing_full) throw StopSearch{};
    }
    batch.clear();
  };
  auto callback = [&](const Box& x, const Box& y) {
    const int64_t f = std::min(x.info(), y.info()), g = std::max(x.info(), y.info());
    if (options.on_box_pair) options.on_box_pair(f, g);
    const auto &a = mesh.faces[f], &b = mesh.faces[g];
    for (int32_t v : a) {
      if (v == b[0] || v == b[1] || v == b[2]) return;  // pairs sharing a vertex: not tested
    }
    batch.push_back({f, g, 0, false});
    if (batch.size() == kBatch) test_batch();
  };
  try {
    if (options.candidates) {
      ForCandidatePairs(options.candidates->faces, make_box, options.focus_faces, callback);
    } else {
      ForIntersectingBoxes(nf, make_box, options.focus_faces, options.boxes_per_slab, callback);
    }
    test_batch();
  } catch (const StopSearch&) {
  }
  r->close_face_pairs_truncated = close_full;
  r->float_intersections_truncated = crossing_full;
  std::sort(close.begin(), close.end());
  close.erase(std::unique(close.begin(), close.end()), close.end());
  std::sort(crossing.begin(), crossing.end());
  crossing.erase(std::unique(crossing.begin(), crossing.end()), crossing.end());
  r->num_close_face_pairs = static_cast<int64_t>(close.size());
  std::vector<std::array<int64_t, 2>> pairs;
  for (const auto& [pair, d] : close) {
    pairs.push_back(pair);
    r->closest_face_pair_distance = std::min(r->closest_face_pair_distance.value_or(d), d);
  }
  AddExamples(pairs, options.max_examples, &r->close_face_pair_examples);
  r->num_float_intersections = static_cast<int64_t>(crossing.size());
  AddExamples(crossing, options.max_examples, &r->float_intersection_examples);
  const double seconds = timer.Seconds();
  if (seconds > 1.0) {
    spdlog::info(
        "float robustness: {} faces, {} pairs sharing no vertex tested, {} closer than {:.3g}, "
        "{} intersecting in double precision, in {:.1f} s",
        std::count_if(usable.begin(), usable.end(), [](uint8_t u) { return u != 0; }), tested,
        close.size(), tol, crossing.size(), seconds);
  }
}

}  // namespace

void FloatRobustnessOptions::Check() const {
  if (!(relative_tolerance >= 0) || !std::isfinite(relative_tolerance)) {
    throw InputError(fmt::format("--float-tolerance must be >= 0, got {}", relative_tolerance));
  }
  if (!(absolute_tolerance >= 0) || !std::isfinite(absolute_tolerance)) {
    throw InputError(fmt::format("--float-tolerance-abs must be >= 0, got {}", absolute_tolerance));
  }
  if (max_examples < 0) throw InputError("mesh check: max_examples must be >= 0");
  if (max_pairs < 1) throw InputError("mesh check: max_self_intersections must be >= 1");
  if (boxes_per_slab < 1) throw InputError("mesh check: boxes_per_slab must be >= 1");
}

namespace {

// The bounding box of the usable faces' vertices, and which vertices they reference.
void UsableBounds(const Mesh& mesh, const std::vector<uint8_t>& usable, Eigen::Vector3d* lo,
                  Eigen::Vector3d* hi, std::vector<uint8_t>* referenced) {
  MS_CHECK(usable.size() == mesh.faces.size());
  *lo = Eigen::Vector3d::Constant(INFINITY);
  *hi = -*lo;
  if (referenced != nullptr) referenced->assign(mesh.vertices.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!usable[f]) continue;
    for (int32_t v : mesh.faces[f]) {
      if (referenced != nullptr) (*referenced)[v] = 1;
      *lo = lo->cwiseMin(mesh.vertices[v]);
      *hi = hi->cwiseMax(mesh.vertices[v]);
    }
  }
}

void SetTolerance(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                  const FloatRobustnessOptions& options, FloatRobustnessReport* r) {
  r->diagonal = (lo.array() <= hi.array()).all() ? (hi - lo).norm() : 0.0;
  r->tolerance = options.absolute_tolerance > 0 ? options.absolute_tolerance
                                                : options.relative_tolerance * r->diagonal;
  r->relative_tolerance =
      options.absolute_tolerance > 0
          ? (r->diagonal > 0 && std::isfinite(r->diagonal) ? r->tolerance / r->diagonal : 0.0)
          : options.relative_tolerance;
}

}  // namespace

PairCandidates FindPairCandidates(const Mesh& mesh, const std::vector<Eigen::Vector3d>& to,
                                  double tolerance, const std::vector<uint8_t>& focus) {
  MS_CHECK(to.size() == mesh.vertices.size() &&
           (focus.empty() || focus.size() == mesh.faces.size()))
      << "pair candidates: " << to.size() << " places for " << mesh.vertices.size() << " vertices, "
      << focus.size() << " flags for " << mesh.faces.size() << " faces";
  // The box of vertex v's two places, added to [lo, hi].
  const auto add_places = [&](int32_t v, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
    *lo = lo->cwiseMin(mesh.vertices[v].cwiseMin(to[v]));
    *hi = hi->cwiseMax(mesh.vertices[v].cwiseMax(to[v]));
  };
  const Eigen::Vector3d slack = Eigen::Vector3d::Constant(tolerance);
  const auto grown_box = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int64_t id,
                             SearchBox* box) {
    if (!lo.allFinite() || !hi.allFinite()) return false;
    *box = SearchBox(lo - slack, hi + slack, id);
    return true;
  };
  const Eigen::Vector3d empty_lo =
      Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  const auto make_face_box = [&](int64_t f, SearchBox* box) {
    Eigen::Vector3d lo = empty_lo, hi = -empty_lo;
    for (int32_t v : mesh.faces[f]) {
      if (v < 0 || static_cast<size_t>(v) >= mesh.vertices.size()) return false;
      add_places(v, &lo, &hi);
    }
    return grown_box(lo, hi, f, box);
  };
  const auto make_vertex_box = [&](int64_t v, SearchBox* box) {
    Eigen::Vector3d lo = empty_lo, hi = -empty_lo;
    add_places(static_cast<int32_t>(v), &lo, &hi);
    return grown_box(lo, hi, v, box);
  };
  // Each pair once, smaller index first.
  const auto collect = [](std::vector<std::array<int32_t, 2>>* pairs) {
    return [pairs](const SearchBox& x, const SearchBox& y) {
      const auto a = static_cast<int32_t>(x.info()), b = static_cast<int32_t>(y.info());
      pairs->push_back({std::min(a, b), std::max(a, b)});
    };
  };
  const int64_t per_slab = FloatRobustnessOptions().boxes_per_slab;
  PairCandidates c;
  ForIntersectingBoxes(static_cast<int64_t>(mesh.faces.size()), make_face_box, focus, per_slab,
                       collect(&c.faces));
  ForIntersectingBoxes(static_cast<int64_t>(mesh.vertices.size()), make_vertex_box,
                       VerticesOfFlaggedFaces(mesh, focus), per_slab, collect(&c.vertices));
  for (auto* pairs : {&c.faces, &c.vertices}) {
    std::sort(pairs->begin(), pairs->end());
    pairs->erase(std::unique(pairs->begin(), pairs->end()), pairs->end());
    pairs->shrink_to_fit();
  }
  return c;
}

double FloatCheckTolerance(const Mesh& mesh, const std::vector<uint8_t>& usable,
                           const FloatRobustnessOptions& options) {
  options.Check();
  FloatRobustnessReport r;
  Eigen::Vector3d lo, hi;
  UsableBounds(mesh, usable, &lo, &hi, nullptr);
  SetTolerance(lo, hi, options, &r);
  return r.tolerance;
}

FloatRobustnessReport CheckFloatRobustness(const Mesh& mesh, const std::vector<uint8_t>& usable,
                                           const FloatRobustnessOptions& options) {
  options.Check();
  if (!options.focus_faces.empty() && options.focus_faces.size() != mesh.faces.size()) {
    throw InputError(fmt::format("float check: {} focus flags for {} faces",
                                 options.focus_faces.size(), mesh.faces.size()));
  }
  FloatRobustnessReport r;
  std::vector<uint8_t> referenced;
  Eigen::Vector3d lo, hi;
  UsableBounds(mesh, usable, &lo, &hi, &referenced);
  SetTolerance(lo, hi, options, &r);

  Timer timer;
  MeasureFaces(mesh, usable, options.focus_faces, &r);
  const double measure_seconds = timer.Seconds();
  timer.Restart();
  FindNearVertices(mesh, referenced, options, &r);
  const double vertex_seconds = timer.Seconds();
  timer.Restart();
  r.face_pairs_checked = options.check_face_pairs;
  if (options.check_face_pairs) FindCloseFacePairs(mesh, usable, options, &r);
  spdlog::debug(
      "float robustness: edges and angles {:.2f} s, near vertices {:.2f} s, face pairs {:.2f} s",
      measure_seconds, vertex_seconds, timer.Seconds());
  return r;
}

}  // namespace ms
