// The triangulation under the manifold: CGAL's 3D Delaunay triangulation (exact predicates,
// inexact constructions) and what its vertices and cells carry. Internal to manifold/: only the
// library's own files include it; the public header, delaunay_manifold.h, has no CGAL type.
#pragma once

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <climits>
#include <cstdint>

namespace ms::manifold_detail {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

inline constexpr int32_t kInfiniteVertexId = INT32_MAX;

struct VertexInfo {
  int32_t id = kInfiniteVertexId;  // point id (>= 0) or -1 - k for Steiner point k
  int32_t outside_cells = 0;       // incident cells in O
  int32_t cells = 0;               // incident cells, infinite ones included
  int32_t surface_faces = 0;       // incident faces between O and the rest
  uint32_t changed = 0;            // last insertion batch that changed a cell around it
  uint32_t relabelled = 0;         // CellLabels::relabels() when a cell around it last flipped
};

// 20 bytes, which CGAL's cell (8 handles and a byte of its own) lays out in 88 bytes: at 5 cells
// a point every 4 bytes here cost 20 bytes a point (docs/design/scalability.md, "Memory per
// point").
struct CellInfo {
  // A spread count at this value lives in CellLabels' overflow table: only cells beside the
  // cameras of large scenes pass 65,534.
  static constexpr uint16_t kSpreadOverflow = UINT16_MAX;
  // Parts an insertion may number (born's bits).
  static constexpr uint32_t kMaxPart = (1u << 28) - 1;
  CellInfo() : born(0), outside(0), queued(0), has_camera(0), frozen(0) {}
  int32_t crossings = 0;  // viewing rays whose open segment meets the open cell
  // Of those, the rays that spread w2 across face i to the neighbour there (see
  // CellLabels::Weight; read through CellLabels::Spread).
  uint16_t spread[4] = {0, 0, 0, 0};
  uint32_t stamp = 0;    // visit marker for walks and set building (RayWalker::NextStamp)
  uint32_t born : 28;    // insertion part that created the cell (0: the initial build)
  uint32_t outside : 1;  // in O
  uint32_t queued : 1;   // in the growing queue
  uint32_t has_camera : 1;
  // Another tile owns the cell (tile_manifold.h): its label is that tile's, set from outside,
  // and never free here.
  uint32_t frozen : 1;
};

using Vb = CGAL::Triangulation_vertex_base_with_info_3<VertexInfo, Kernel>;
using Cb =
    CGAL::Triangulation_cell_base_with_info_3<CellInfo, Kernel,
                                              CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;
using Cell_handle = Delaunay::Cell_handle;
using Vertex_handle = Delaunay::Vertex_handle;
using Facet = Delaunay::Facet;
using Locate_type = Delaunay::Locate_type;

inline Point ToPoint(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }
inline Eigen::Vector3d ToEigen(const Point& p) { return Eigen::Vector3d(p.x(), p.y(), p.z()); }

// A cell's name independent of memory layout: the ids of its vertices, sorted. Unique among the
// finite cells; orders the growing queue's ties and the shrink set.
using CellKey = std::array<int32_t, 4>;

inline CellKey KeyOf(const Cell_handle& c) {
  CellKey key;
  for (int i = 0; i < 4; ++i) key[i] = c->vertex(i)->info().id;
  std::sort(key.begin(), key.end());
  return key;
}

}  // namespace ms::manifold_detail
