// The coverage rules every rasteriser of the sweep shares (sweep/software_raster.h,
// sweep/span_raster.h), so that they cover exactly the same pixels: edge functions evaluated
// from the lexicographically smaller endpoint (triangles sharing an edge compute exactly
// opposite values) and the top-left fill rule in y-down image coordinates.
#pragma once

namespace ms::raster {

struct Point2 {
  double x, y;
};

inline bool Before(const Point2& a, const Point2& b) {
  return a.x < b.x || (a.x == b.x && a.y < b.y);
}

// Edge function of p against the directed edge a->b: positive on the left of a->b in y-down
// coordinates when the triangle is oriented so that Edge(p0, p1, p2) > 0.
inline double Edge(const Point2& a, const Point2& b, const Point2& p) {
  if (Before(b, a)) {
    return -((a.x - b.x) * (p.y - b.y) - (a.y - b.y) * (p.x - b.x));
  }
  return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Top edge (horizontal, interior below) or left edge (going up) for the orientation above.
inline bool TopLeft(const Point2& a, const Point2& b) {
  const double dy = b.y - a.y;
  return dy < 0 || (dy == 0 && b.x > a.x);
}

inline bool Covers(double w, const Point2& a, const Point2& b) {
  return w > 0 || (w == 0 && TopLeft(a, b));
}

}  // namespace ms::raster
