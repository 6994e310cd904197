// The only translation unit that sees CGAL's Delaunay triangulation (compile time, see
// docs/manifold.md for the algorithm and its invariants).
#include "manifold/delaunay_manifold.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <queue>
#include <sstream>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "base/check.h"
#include "base/error.h"
#include "base/log.h"
#include "manifold/manifold_internal.h"
#include "manifold/ray_index.h"
#include "manifold/steiner_points.h"

namespace ms {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

constexpr int32_t kInfiniteVertexId = INT32_MAX;

struct VertexInfo {
  int32_t id = kInfiniteVertexId;  // point id (>= 0) or -1 - k for Steiner point k
  int32_t outside_cells = 0;       // incident cells in O
  int32_t cells = 0;               // incident cells, infinite ones included
  int32_t surface_faces = 0;       // incident faces between O and the rest
  uint32_t changed = 0;            // last insertion batch that changed a cell around it
};

struct CellInfo {
  int32_t crossings = 0;  // viewing rays whose open segment meets the open cell
  // Of those, the rays that spread w2 across face i to the neighbour there (see Weight).
  int32_t spread[4] = {0, 0, 0, 0};
  uint32_t stamp = 0;     // visit marker for walks and set building
  uint32_t born = 0;      // insertion batch that created the cell (0: the initial build)
  bool outside = false;   // in O
  bool queued = false;    // in the growing queue
  bool has_camera = false;
};

using Vb = CGAL::Triangulation_vertex_base_with_info_3<VertexInfo, Kernel>;
using Cb = CGAL::Triangulation_cell_base_with_info_3<CellInfo, Kernel,
                                                     CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;
using Cell_handle = Delaunay::Cell_handle;
using Vertex_handle = Delaunay::Vertex_handle;
using Facet = Delaunay::Facet;
using Locate_type = Delaunay::Locate_type;

Point ToPoint(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }

// Sign of K_ij = A_j B_i - A_i B_j is kPluckerSign[i][j] * orientation(p_k, p_l, a, b) for a
// positively oriented cell, where {k < l} are the two other indices (a Grassmann-Pluecker
// identity; A_i, B_i are the orientations of a and b against face i).
constexpr int kPluckerSign[4][4] = {{0, -1, 1, -1}, {1, 0, -1, 1}, {-1, 1, 0, -1}, {1, -1, 1, 0}};

// Fast walk step: entering a cell through face e, the segment leaves through the face given
// by the signs of orientation(p_e, p_m, a, b) for the three other vertices m (in increasing
// order), coded as 4*(s1>0) + 2*(s2>0) + (s3>0). Codes 0 and 7 cannot occur; a zero sign is a
// degenerate step handled by the general rule. (Derived and checked numerically.)
constexpr int kExitFace[4][8] = {{-1, 1, 3, 3, 2, 1, 2, -1},
                                 {-1, 2, 0, 2, 3, 3, 0, -1},
                                 {-1, 0, 3, 3, 1, 0, 1, -1},
                                 {-1, 1, 0, 1, 2, 2, 0, -1}};

// Asks for the cache lines of a cell (vertices, neighbours and info span two).
void PrefetchCell(const Cell_handle& c) {
  const char* bytes = reinterpret_cast<const char*>(&*c);
  __builtin_prefetch(bytes);
  __builtin_prefetch(bytes + 64);
}

void OtherTwo(int i, int j, int* k, int* l) {
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
int FastExitFace(const Cell_handle& c, int entry, const Point& a, const Point& b) {
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

FaceSides ComputeFaceSides(const Cell_handle& c, const Point& a, const Point& b) {
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
CGAL::Orientation FaceSide(const Cell_handle& c, int i, const Point& x) {
  const Point* p[4] = {&c->vertex(0)->point(), &c->vertex(1)->point(), &c->vertex(2)->point(),
                       &c->vertex(3)->point()};
  p[i] = &x;
  return CGAL::orientation(*p[0], *p[1], *p[2], *p[3]);
}

// Sign of K_ij (see kPluckerSign).
int PluckerSign(const Cell_handle& c, int i, int j, const Point& a, const Point& b) {
  int k, l;
  OtherTwo(i, j, &k, &l);
  return kPluckerSign[i][j] *
         static_cast<int>(CGAL::orientation(c->vertex(k)->point(), c->vertex(l)->point(), a, b));
}

// Exact test: does the open segment (a, b) meet the open (finite) cell? Along the segment,
// face i's orientation is (1-t) A_i + t B_i; the segment is inside for the t where all four
// are positive: an interval bounded below by faces with A <= 0 < B and above by faces with
// A > 0 >= B. It is non-empty iff every lower bound is below every upper bound.
bool SegmentCrossesCell(const Cell_handle& c, const Point& a, const Point& b, const FaceSides& s) {
  int lower[4], upper[4], nl = 0, nu = 0;
  for (int i = 0; i < 4; ++i) {
    if (s.a[i] <= 0 && s.b[i] <= 0) return false;
    if (s.a[i] <= 0) lower[nl++] = i;
    else if (s.b[i] <= 0) upper[nu++] = i;
  }
  for (int x = 0; x < nl; ++x) {
    for (int y = 0; y < nu; ++y) {
      if (PluckerSign(c, lower[x], upper[y], a, b) <= 0) return false;
    }
  }
  return true;
}

bool SegmentCrossesCell(const Cell_handle& c, const Point& a, const Point& b) {
  return SegmentCrossesCell(c, a, b, ComputeFaceSides(c, a, b));
}

// The faces of a crossed cell with the camera beyond them (`camera_sides`: the camera's row of
// FaceSides): a ray from that camera spreads w2 across them (the walks' visit mask).
unsigned CameraSideMask(const int camera_sides[4]) {
  unsigned mask = 0;
  for (int i = 0; i < 4; ++i) mask |= (camera_sides[i] < 0 ? 1u : 0u) << i;
  return mask;
}

// The face through which the open segment a -> b leaves the crossed cell c (s: its sides from
// ComputeFaceSides(c, a, b)): among the faces with a inside and b beyond or on, the one whose
// bound on the segment's parameter comes first; -1 if none. ties[0, *num_ties) are the faces
// tying for it: two mean leaving through an edge, three through a vertex.
int ExitFace(const Cell_handle& c, const Point& a, const Point& b, const FaceSides& s,
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
bool SegmentMeetsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi, double* entry) {
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

using CellKey = std::array<int32_t, 4>;

struct QueueEntry {
  double weight;
  CellKey key;
  Cell_handle cell;
  // Max-heap: heavier first; among equal weights the smaller key first (determinism).
  bool operator<(const QueueEntry& o) const {
    if (weight != o.weight) return weight < o.weight;
    return key > o.key;
  }
};

}  // namespace

struct ManifoldTestAccess;

class DelaunayManifold::Impl {
 public:
  Impl(std::vector<ManifoldCamera> cameras, const ManifoldOptions& options)
      : options_(options), cameras_(std::move(cameras)) {
    options_.Check();
    for (size_t c = 0; c < cameras_.size(); ++c) {
      if (!cameras_[c].center.allFinite() || !cameras_[c].R.allFinite()) {
        throw InputError("camera " + std::to_string(c) + ": pose is not finite");
      }
    }
    std::vector<RayIndex::Camera> index_cameras;
    for (const ManifoldCamera& c : cameras_) {
      index_cameras.push_back({c.R, c.center, c.u_min, c.u_max, c.v_min, c.v_max});
    }
    ray_index_ = std::make_unique<RayIndex>(std::move(index_cameras));
    camera_cells_.resize(cameras_.size());
  }

  BuildStats Build(const std::vector<RayPoint>& points);
  InsertionStats Insert(const std::vector<RayPoint>& points);
  Mesh ExtractSurface(SurfaceInfo* info) const;
  std::string Validate(bool check_weights) const;

  friend struct ManifoldTestAccess;
  int64_t num_points() const { return static_cast<int64_t>(positions_.size()); }
  int64_t num_vertices() const { return static_cast<int64_t>(dt_.number_of_vertices()); }
  int64_t num_cells() const { return static_cast<int64_t>(dt_.number_of_finite_cells()); }
  int64_t num_outside_cells() const { return outside_count_; }
  // Free cells that growing left out of O (refused by the manifold test or unreachable).
  int64_t CountFreeCellsInside() const {
    int64_t n = 0;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      n += !c->info().outside && IsFree(c);
    }
    return n;
  }
  size_t MemoryBytes() const {
    return dt_.number_of_cells() * sizeof(Delaunay::Cell) +
           dt_.number_of_vertices() * sizeof(Delaunay::Vertex) +
           positions_.capacity() * sizeof(Eigen::Vector3d) +
           point_cameras_.capacity() * sizeof(std::vector<int32_t>) +
           ray_index_->size() * sizeof(int32_t) +
           vertex_of_point_.capacity() * sizeof(Vertex_handle) + ray_index_->MemoryBytes();
  }

 private:
  struct CameraStart {
    bool valid = false;
    Cell_handle cell;
    Locate_type type = Delaunay::CELL;
    int li = 0, lj = 0;
  };

  // --- labels and weights ---
  bool InO(const Cell_handle& c) const { return !dt_.is_infinite(c) && c->info().outside; }
  // w1 per ray crossing c, plus w2 per ray crossing a face neighbour n that spreads across
  // the face n shares with c.
  double Weight(const Cell_handle& c) const {
    int64_t neighbours = 0;
    for (int i = 0; i < 4; ++i) {
      const Cell_handle n = c->neighbor(i);
      neighbours += n->info().spread[n->index(c)];
    }
    return options_.w1 * c->info().crossings + options_.w2 * static_cast<double>(neighbours);
  }
  // Counts one ray crossing c; bit i of `spread_mask` says it spreads w2 across face i.
  void CountCrossing(const Cell_handle& c, unsigned spread_mask) const {
    CellInfo& info = c->info();
    ++info.crossings;
    if (options_.w2_rule == W2Rule::kAllFaces) spread_mask = 0xF;
    for (int i = 0; i < 4; ++i) info.spread[i] += (spread_mask >> i) & 1;
  }
  bool IsFree(const Cell_handle& c) const {
    if (dt_.is_infinite(c)) return false;
    // With graded Steiner points, a cell of Steiner points only is empty space (no input point
    // in its circumsphere): free without rays, so the free space stays one region around the
    // cameras instead of narrow cones that growing cannot carve (docs/manifold.md).
    if (graded_ && c->vertex(0)->info().id < 0 && c->vertex(1)->info().id < 0 &&
        c->vertex(2)->info().id < 0 && c->vertex(3)->info().id < 0) {
      return true;
    }
    return Weight(c) >= options_.free_threshold;
  }
  void SetOutside(const Cell_handle& c, bool outside) {
    MS_CHECK(!dt_.is_infinite(c));
    if (c->info().outside == outside) return;
    c->info().outside = outside;
    const int delta = outside ? 1 : -1;
    outside_count_ += delta;
    for (int i = 0; i < 4; ++i) c->vertex(i)->info().outside_cells += delta;
    // Flipping c toggles whether each of its faces is on the surface.
    for (int i = 0; i < 4; ++i) {
      const int face_delta = InO(c->neighbor(i)) != outside ? 1 : -1;
      for (int j = 0; j < 4; ++j) {
        if (j != i) c->vertex(j)->info().surface_faces += face_delta;
      }
    }
  }
  CellKey Key(const Cell_handle& c) const {
    CellKey key;
    for (int i = 0; i < 4; ++i) key[i] = c->vertex(i)->info().id;
    std::sort(key.begin(), key.end());
    return key;
  }

  // --- manifold tests ---
  bool FlipKeepsManifold(const Cell_handle& t) const;
  bool VertexRegular(const Vertex_handle& v, const Cell_handle& flipped) const;
  bool VertexRegularAfterFlip(const Vertex_handle& v, const Cell_handle& t) const;

  // --- growing and shrinking ---
  void Grow(const std::vector<Cell_handle>& seeds);
  int64_t GrowFromHeaviest();
  // Cells not in O, sharing a face with O, with a vertex marked changed in batch `changed_in`.
  std::vector<Cell_handle> BoundarySeeds(uint32_t changed_in) const;
  // --- rays ---
  uint32_t NextStamp() const;
  const CameraStart& StartOf(int camera);
  // Calls visit(cell) for every cell crossed by the open segment camera -> point.
  template <typename Visit>
  int64_t Walk(const CameraStart& start, const Point& a, const Vertex_handle& target,
               Visit&& visit) const;
  template <typename Visit>
  void WalkFallback(Cell_handle from, const Point& a, const Point& b, uint32_t stamp,
                    Visit& visit) const;
  std::vector<Cell_handle> StartCandidates(const CameraStart& start) const;
  // Walks the open segment a -> target backwards from the target and calls visit(cell, mask)
  // (masks as Walk's) for the cells it crosses at parameters >= reach (0 at a, 1 at the
  // target) for which wants(cell) holds, stopping at the first cell lying wholly before reach.
  // Returns false, having visited nothing, where the segment runs along a face or an edge:
  // then walk forwards.
  template <typename Wants, typename Visit>
  bool WalkBack(const Point& a, const Vertex_handle& target, double reach, Wants&& wants,
                Visit&& visit, int64_t* steps) const;

  ManifoldOptions options_;
  std::vector<ManifoldCamera> cameras_;
  std::vector<Point> camera_points_;
  std::vector<CameraStart> camera_cells_;
  mutable Delaunay dt_;
  std::unique_ptr<RayIndex> ray_index_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<std::vector<int32_t>> point_cameras_;
  std::vector<Vertex_handle> vertex_of_point_;
  Eigen::Vector3d box_min_, box_max_;  // Steiner box: points outside are discarded
  int64_t steiner_count_ = 0;
  int64_t outside_count_ = 0;
  mutable uint32_t stamp_ = 0;
  uint32_t batch_ = 0;               // insertion batches so far
  mutable std::vector<Cell_handle> scratch_cells_;  // reused by walks
  mutable std::vector<std::pair<Cell_handle, unsigned>> scratch_crossed_;  // by WalkBack
  struct TestCounts {
    int64_t fast = 0, full = 0, link_steps = 0;
  };
  mutable TestCounts test_counts_;
  // Reused by VertexRegular (no allocation in the hot path).
  mutable std::vector<Cell_handle> regular_cells_;
  mutable std::vector<std::pair<Vertex_handle, Vertex_handle>> regular_link_;
  mutable std::vector<std::pair<Vertex_handle, int>> regular_degree_;
  bool built_ = false;
  bool graded_ = false;  // graded Steiner points in use (decided by Build)
};

// ---------------------------------------------------------------------------------------------
// Ray walking

uint32_t DelaunayManifold::Impl::NextStamp() const {
  if (++stamp_ == 0) {
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) c->info().stamp = 0;
    stamp_ = 1;
  }
  return stamp_;
}

const DelaunayManifold::Impl::CameraStart& DelaunayManifold::Impl::StartOf(int camera) {
  CameraStart& start = camera_cells_[camera];
  if (!start.valid) {
    start.cell = dt_.locate(camera_points_[camera], start.type, start.li, start.lj);
    start.valid = true;
    start.cell->info().has_camera = true;
  }
  return start;
}

std::vector<Cell_handle> DelaunayManifold::Impl::StartCandidates(const CameraStart& start) const {
  std::vector<Cell_handle> cells;
  switch (start.type) {
    case Delaunay::CELL:
      cells.push_back(start.cell);
      break;
    case Delaunay::FACET:
      cells.push_back(start.cell);
      cells.push_back(start.cell->neighbor(start.li));
      break;
    case Delaunay::EDGE: {
      auto circ = dt_.incident_cells(start.cell, start.li, start.lj), done = circ;
      do {
        cells.push_back(circ);
      } while (++circ != done);
      break;
    }
    case Delaunay::VERTEX:
      dt_.incident_cells(start.cell->vertex(start.li), std::back_inserter(cells));
      break;
    default:
      MS_CHECK(false) << "camera outside the triangulation (locate type " << start.type << ")";
  }
  return cells;
}

template <typename Visit>
int64_t DelaunayManifold::Impl::Walk(const CameraStart& start, const Point& a,
                                     const Vertex_handle& target, Visit&& visit) const {
  const Point& b = target->point();
  const uint32_t stamp = NextStamp();
  int64_t steps = 0;
  Cell_handle current;
  if (start.type == Delaunay::CELL) {
    current = start.cell;  // the camera is strictly inside: the segment starts in this cell
  } else {
    const std::vector<Cell_handle> candidates = StartCandidates(start);
    for (const Cell_handle& c : candidates) {
      if (!dt_.is_infinite(c) && SegmentCrossesCell(c, a, b)) {
        current = c;
        break;
      }
    }
    if (current == Cell_handle()) {
      // The segment leaves the camera along a face or edge: enumerate exhaustively.
      WalkFallback(candidates.front(), a, b, stamp, visit);
      return steps;
    }
  }
  int entry = -1;  // face through which `current` was entered, if through a face interior
  for (;;) {
    // The next cell is one of these: start loading them (both cache lines a cell spans) while
    // the orientations are computed.
    for (int i = 0; i < 4; ++i) {
      if (i != entry) PrefetchCell(current->neighbor(i));
    }
    current->info().stamp = stamp;
    ++steps;
    Cell_handle next;
    int exit = -1;
    // A crossed cell incident to the end point is the last one (convexity).
    const bool last = current->has_vertex(target);
    if (entry >= 0 && !last) {
      exit = FastExitFace(current, entry, a, b);
    }
    if (exit >= 0) {
      // The camera is beyond the entry face and before the exit face; test the other two.
      unsigned mask = 1u << entry;
      for (int i = 0; i < 4; ++i) {
        if (i != entry && i != exit && FaceSide(current, i, a) == CGAL::NEGATIVE) mask |= 1u << i;
      }
      visit(current, mask);
    } else {
      // General step, exact in every case: the exit is the face whose bound on the segment's
      // parameter is smallest; ties mean leaving through an edge or a vertex.
      const FaceSides s = ComputeFaceSides(current, a, b);
      visit(current, CameraSideMask(s.a));
      if (last) break;
      int ties[3], num_ties = 0;
      exit = ExitFace(current, a, b, s, ties, &num_ties);
      if (exit < 0 || s.b[exit] == 0) break;  // the segment ends in or on this cell
      if (num_ties > 1) {
        // Leaves through an edge (two faces tie) or a vertex (three): the next cell is the
        // one around that simplex that the segment enters.
        std::vector<Cell_handle>& around = scratch_cells_;
        around.clear();
        if (num_ties == 2) {
          int k, l;
          OtherTwo(ties[0], ties[1], &k, &l);
          auto circ = dt_.incident_cells(current, k, l), done = circ;
          do {
            around.push_back(circ);
          } while (++circ != done);
        } else {
          const int vertex = 6 - ties[0] - ties[1] - ties[2];
          dt_.incident_cells(current->vertex(vertex), std::back_inserter(around));
        }
        for (const Cell_handle& c : around) {
          if (c->info().stamp != stamp && !dt_.is_infinite(c) && SegmentCrossesCell(c, a, b)) {
            next = c;
            break;
          }
        }
        if (next == Cell_handle()) {
          // Degenerate: the segment runs inside a face or along an edge for a while.
          WalkFallback(current, a, b, stamp, visit);
          return steps;
        }
        entry = -1;
        current = next;
        continue;
      }
    }
    next = current->neighbor(exit);
    MS_CHECK(!dt_.is_infinite(next)) << "viewing ray leaves the triangulation";
    if (next->info().stamp == stamp) {
      WalkFallback(current, a, b, stamp, visit);
      return steps;
    }
    entry = next->index(current);
    current = next;
  }
  return steps;
}

template <typename Wants, typename Visit>
bool DelaunayManifold::Impl::WalkBack(const Point& a, const Vertex_handle& target, double reach,
                                      Wants&& wants, Visit&& visit, int64_t* steps) const {
  const Point& b = target->point();
  const Eigen::Vector3d origin(a.x(), a.y(), a.z());
  const Eigen::Vector3d d = Eigen::Vector3d(b.x(), b.y(), b.z()) - origin;
  const double length2 = d.squaredNorm();
  // Projections of a cell's vertices on the segment (scaled by |d|^2: 0 at a, length2 at b).
  // All before `reach` (with slack for rounding): the cell holds no part of the segment at or
  // beyond it. All of the exit face's: nor do the cells further towards a. None at or before
  // 0: a is not in the cell.
  const double limit = (reach - 1e-9) * length2, near_a = 1e-9 * length2;
  double t[4];
  const auto project = [&](const Cell_handle& c) {
    for (int i = 0; i < 4; ++i) {
      const Point& q = c->vertex(i)->point();
      t[i] = (Eigen::Vector3d(q.x(), q.y(), q.z()) - origin).dot(d);
    }
  };
  const auto before_reach_except = [&](int skip) {
    for (int i = 0; i < 4; ++i) {
      if (i != skip && t[i] >= limit) return false;
    }
    return true;
  };

  // The first cell: the one around the target whose three faces through the target have a
  // strictly on their inner side (the segment leaves the target into its interior). Found by
  // a visibility walk in the target's star; a zero orientation means the segment runs along a
  // face or an edge there.
  Cell_handle current = target->cell();
  uint32_t stamp = NextStamp();
  for (int star_steps = 0;; ++star_steps) {
    if (dt_.is_infinite(current) || current->info().stamp == stamp || star_steps > 64) {
      return false;  // not expected inside the Steiner box; the forward walk is exact
    }
    current->info().stamp = stamp;
    const int at = current->index(target);
    int across = -1;
    bool on_face = false;
    for (int j = 0; j < 4 && across < 0; ++j) {
      if (j == at) continue;
      const CGAL::Orientation o = FaceSide(current, j, a);
      if (o == CGAL::NEGATIVE) across = j;
      on_face |= o == CGAL::COPLANAR;
    }
    if (across >= 0) {
      current = current->neighbor(across);
      continue;
    }
    if (on_face) return false;
    break;
  }

  stamp = NextStamp();
  std::vector<std::pair<Cell_handle, unsigned>>& crossed = scratch_crossed_;
  crossed.clear();
  // The segment from the target towards a enters each cell through face `entry` (-1: the
  // first cell, left through the face opposite the target unless a is in it).
  int entry = -1;
  int64_t walked = 0;
  for (;;) {
    for (int i = 0; i < 4; ++i) {
      if (i != entry) PrefetchCell(current->neighbor(i));  // as in Walk
    }
    project(current);
    // Only the first cell can lie wholly before reach: every later one shares the previous
    // cell's exit face, which has a vertex at or past it (checked below).
    if (entry < 0 && before_reach_except(-1)) break;
    const double lowest = std::min(std::min(t[0], t[1]), std::min(t[2], t[3]));
    current->info().stamp = stamp;
    ++walked;
    int exit = -1;
    if (entry < 0) {
      exit = current->index(target);
    } else {
      exit = FastExitFace(current, entry, b, a);  // the segment b -> a
    }
    if (exit >= 0) {
      // a lies in this cell only if it is on the inner side of the exit face.
      const bool ends_here = lowest <= near_a && FaceSide(current, exit, a) != CGAL::NEGATIVE;
      if (wants(current)) {
        // a in the cell is beyond none of its faces. Otherwise, forwards, the ray enters
        // through our exit face (a beyond it) and leaves through our entry face (a before it);
        // the other two are tested (in the first cell they pass through the target, with a
        // strictly inside them).
        unsigned mask = 0;
        if (!ends_here) {
          mask = 1u << exit;
          for (int i = 0; i < 4 && entry >= 0; ++i) {
            if (i != exit && i != entry && FaceSide(current, i, a) == CGAL::NEGATIVE) {
              mask |= 1u << i;
            }
          }
        }
        crossed.push_back({current, mask});
      }
      if (ends_here) break;
    } else {
      // General step, exact: the segment from the target towards a: s.a holds the target's
      // sides, s.b the camera's.
      const FaceSides s = ComputeFaceSides(current, b, a);
      if (wants(current)) crossed.push_back({current, CameraSideMask(s.b)});
      int ties[3], num_ties = 0;
      exit = ExitFace(current, b, a, s, ties, &num_ties);
      if (exit < 0 || s.b[exit] == 0) break;  // a is in or on this cell
      if (num_ties > 1) return false;          // leaves through an edge or a vertex
    }
    if (before_reach_except(exit)) break;
    const Cell_handle next = current->neighbor(exit);
    if (dt_.is_infinite(next) || next->info().stamp == stamp) return false;
    entry = next->index(current);
    current = next;
  }
  for (const auto& [cell, cell_mask] : crossed) visit(cell, cell_mask);
  *steps += walked;
  return true;
}

// Exhaustive enumeration for degenerate segments: flood over cells whose closure meets the
// closed segment (exact predicate), connected through shared vertices, and visit the unvisited
// ones that the open segment crosses.
template <typename Visit>
void DelaunayManifold::Impl::WalkFallback(Cell_handle from, const Point& a, const Point& b,
                                          uint32_t stamp, Visit& visit) const {
  const Kernel::Segment_3 segment(a, b);
  std::vector<Cell_handle> stack{from};
  std::unordered_set<const void*> seen{&*from};
  std::vector<Cell_handle> around;
  while (!stack.empty()) {
    const Cell_handle c = stack.back();
    stack.pop_back();
    if (dt_.is_infinite(c)) continue;
    const Kernel::Tetrahedron_3 tet(c->vertex(0)->point(), c->vertex(1)->point(),
                                    c->vertex(2)->point(), c->vertex(3)->point());
    if (c != from && !CGAL::do_intersect(segment, tet)) continue;
    const FaceSides sides = ComputeFaceSides(c, a, b);
    if (c->info().stamp != stamp && SegmentCrossesCell(c, a, b, sides)) {
      c->info().stamp = stamp;
      visit(c, CameraSideMask(sides.a));
    }
    for (int i = 0; i < 4; ++i) {
      around.clear();
      dt_.incident_cells(c->vertex(i), std::back_inserter(around));
      for (const Cell_handle& n : around) {
        if (seen.insert(&*n).second) stack.push_back(n);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Manifold tests

// Would flipping t (into O if it is outside O, out of O otherwise) keep the surface manifold?
// Fast test first (Lhuillier): count the vertices V, edges E and faces F that t shares with
// the side it joins; (0,0,0), (3,3,1), (4,5,2), (4,6,3) and (4,6,4) are always safe. V and F
// are O(1); E is needed only to tell (4,5,2) from (4,6,2). Otherwise the exact test: every
// vertex of t must stay regular.
bool DelaunayManifold::Impl::FlipKeepsManifold(const Cell_handle& t) const {
  const bool joining_outside = !t->info().outside;
  const auto on_target_side = [&](const Cell_handle& c) {
    return c != t && (joining_outside ? InO(c) : !InO(c));
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
  ++test_counts_.fast;
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
  ++test_counts_.full;
  for (int i = 0; i < 4; ++i) {
    if (!VertexRegularAfterFlip(t->vertex(i), t)) return false;
  }
  return true;
}

// Exact and local. The link of v (the edges opposite v in the surface faces around it) is a
// single simple cycle or empty before the flip (the invariant). Flipping t toggles exactly
// the three link edges w1w2, w2w3, w3w1 that t's faces at v contribute. With k of them on the
// link now, the new link is a single cycle or empty iff:
//   k = 0: the link is empty (else a second cycle or a vertex of degree 4 appears);
//   k = 1: say w1w2: it is replaced by w1-w3-w2, fine iff w3 is not on the link already;
//   k = 2: the path w1-w2-w3 is replaced by the edge w1w3: always fine;
//   k = 3: the link was exactly that triangle and becomes empty: fine.
// VertexRegular (the exhaustive criterion) is cross-checked against this in tests.
bool DelaunayManifold::Impl::VertexRegularAfterFlip(const Vertex_handle& v,
                                                    const Cell_handle& t) const {
  const int iv = t->index(v);
  const bool t_outside = InO(t);
  int k = 0, w3 = -1;
  for (int i = 0; i < 4; ++i) {
    if (i == iv) continue;
    // Face i of t (opposite vertex i) contains v; it is on the surface iff labels differ.
    if (t_outside != InO(t->neighbor(i))) {
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
      const bool first = InO(circ);
      bool on_surface = false;
      while (!on_surface && ++circ != done) on_surface = InO(circ) != first;
      ++test_counts_.link_steps;
      return !on_surface;
    }
    default:
      return true;
  }
}

// A vertex is regular when the edges opposite to it in the surface faces around it form one
// closed cycle (or there are none). `flipped` is evaluated with its label inverted.
bool DelaunayManifold::Impl::VertexRegular(const Vertex_handle& v, const Cell_handle& flipped) const {
  const auto label = [&](const Cell_handle& c) { return c == flipped ? !InO(c) : InO(c); };
  std::vector<Cell_handle>& around = regular_cells_;
  around.clear();
  dt_.incident_cells(v, std::back_inserter(around));
  std::vector<std::pair<Vertex_handle, Vertex_handle>>& link = regular_link_;
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
  std::vector<std::pair<Vertex_handle, int>>& degree = regular_degree_;
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

// ---------------------------------------------------------------------------------------------
// Growing

void DelaunayManifold::Impl::Grow(const std::vector<Cell_handle>& seeds) {
  std::priority_queue<QueueEntry> queue;
  const auto push = [&](const Cell_handle& c) {
    if (dt_.is_infinite(c) || c->info().outside || c->info().queued || !IsFree(c)) return;
    c->info().queued = true;
    queue.push({Weight(c), Key(c), c});
  };
  for (const Cell_handle& c : seeds) push(c);
  std::vector<Cell_handle> refused;
  for (;;) {
    int64_t added = 0;
    while (!queue.empty()) {
      const Cell_handle c = queue.top().cell;
      queue.pop();
      c->info().queued = false;
      if (c->info().outside) continue;
      if (FlipKeepsManifold(c)) {
        SetOutside(c, true);
        ++added;
        for (int i = 0; i < 4; ++i) push(c->neighbor(i));
      } else {
        refused.push_back(c);
      }
    }
    // A cell refused earlier may be accepted now that O has changed around it: retry until
    // a round adds nothing.
    if (added == 0 || refused.empty()) break;
    std::vector<Cell_handle> retry;
    retry.swap(refused);
    for (const Cell_handle& c : retry) push(c);
  }
  for (const Cell_handle& c : refused) c->info().queued = false;
}

int64_t DelaunayManifold::Impl::GrowFromHeaviest() {
  const int64_t before = outside_count_;
  for (;;) {
    Cell_handle best;
    QueueEntry best_entry{-1, {}, Cell_handle()};
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (c->info().outside || !IsFree(c)) continue;
      if (outside_count_ > 0) {
        // Later seeds must start a separate component: no vertex touching O.
        bool touches = false;
        for (int i = 0; i < 4; ++i) touches |= c->vertex(i)->info().outside_cells > 0;
        if (touches) continue;
      }
      const QueueEntry entry{Weight(c), Key(c), c};
      if (best == Cell_handle() || best_entry < entry) {
        best = c;
        best_entry = entry;
      }
    }
    if (best == Cell_handle()) break;
    Grow({best});
    if (!options_.grow_all_components) break;
  }
  return outside_count_ - before;
}

std::vector<Cell_handle> DelaunayManifold::Impl::BoundarySeeds(uint32_t changed_in) const {
  std::vector<Cell_handle> seeds;
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    if (c->info().outside) continue;
    bool changed = false;
    for (int i = 0; i < 4; ++i) changed |= c->vertex(i)->info().changed == changed_in;
    if (!changed) continue;
    for (int i = 0; i < 4; ++i) {
      if (InO(c->neighbor(i))) {
        seeds.push_back(c);
        break;
      }
    }
  }
  return seeds;
}

// ---------------------------------------------------------------------------------------------
// Build

BuildStats DelaunayManifold::Impl::Build(const std::vector<RayPoint>& points) {
  if (built_) throw InternalError("DelaunayManifold::Build called twice");
  built_ = true;
  BuildStats stats;
  stats.points = static_cast<int64_t>(points.size());
  Timer timer;

  // Bounding box of points and cameras, Steiner points around it.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (size_t i = 0; i < points.size(); ++i) {
    const RayPoint& p = points[i];
    if (!p.position.allFinite()) {
      throw InputError("point " + std::to_string(i) + ": position is not finite");
    }
    for (int32_t c : p.cameras) {
      if (c < 0 || c >= static_cast<int32_t>(cameras_.size())) {
        throw InputError("point " + std::to_string(i) + ": camera " + std::to_string(c) +
                         " out of range (" + std::to_string(cameras_.size()) + " cameras)");
      }
    }
    lo = lo.cwiseMin(p.position);
    hi = hi.cwiseMax(p.position);
  }
  for (const ManifoldCamera& c : cameras_) {
    lo = lo.cwiseMin(c.center);
    hi = hi.cwiseMax(c.center);
  }
  if (!(lo.array() <= hi.array()).all()) throw InputError("no points and no cameras");
  std::vector<Eigen::Vector3d> data(points.size());
  for (size_t i = 0; i < points.size(); ++i) data[i] = points[i].position;
  SteinerOptions steiner_options;
  steiner_options.margin = options_.steiner_margin;
  steiner_options.grid = options_.steiner_grid;
  graded_ = options_.steiner_graded == GradedSteiner::kOn ||
            (options_.steiner_graded == GradedSteiner::kAuto &&
             static_cast<int64_t>(points.size()) >= options_.graded_steiner_min_points);
  steiner_options.graded = graded_;
  steiner_options.clearance = options_.steiner_clearance;
  steiner_options.min_spacing_factor = options_.steiner_min_spacing;
  const SteinerPoints made = MakeSteinerPoints(lo, hi, data, steiner_options);
  const std::vector<Eigen::Vector3d>& steiner = made.points;
  steiner_count_ = stats.steiner_points = static_cast<int64_t>(steiner.size());
  stats.graded_steiner_points = made.graded;
  box_min_ = Eigen::Vector3d::Constant(INFINITY);
  box_max_ = -box_min_;
  for (const Eigen::Vector3d& s : steiner) {
    box_min_ = box_min_.cwiseMin(s);
    box_max_ = box_max_.cwiseMax(s);
  }

  // (1) Point insertion: Steiner points and input points together (CGAL sorts spatially).
  std::vector<std::pair<Point, VertexInfo>> vertices;
  vertices.reserve(steiner.size() + points.size());
  for (size_t k = 0; k < steiner.size(); ++k) {
    vertices.push_back({ToPoint(steiner[k]), {static_cast<int32_t>(-1 - k), 0, 0, 0, 0}});
  }
  for (size_t i = 0; i < points.size(); ++i) {
    vertices.push_back({ToPoint(points[i].position), {static_cast<int32_t>(i), 0, 0, 0, 0}});
  }
  dt_.insert(vertices.begin(), vertices.end());
  positions_.reserve(points.size());
  point_cameras_.reserve(points.size());
  vertex_of_point_.assign(points.size(), Vertex_handle());
  for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end(); ++v) {
    if (v->info().id >= 0) vertex_of_point_[v->info().id] = v;
  }
  for (size_t i = 0; i < points.size(); ++i) {
    positions_.push_back(points[i].position);
    std::vector<int32_t> cams = points[i].cameras;
    std::sort(cams.begin(), cams.end());
    cams.erase(std::unique(cams.begin(), cams.end()), cams.end());
    point_cameras_.push_back(std::move(cams));
    if (vertex_of_point_[i] == Vertex_handle()) {
      // Same position as another point: its rays end at that vertex.
      Locate_type type;
      int li, lj;
      const Cell_handle c = dt_.locate(ToPoint(points[i].position), type, li, lj);
      MS_CHECK(type == Delaunay::VERTEX) << "point " << i << " not found after insertion";
      vertex_of_point_[i] = c->vertex(li);
      ++stats.merged_duplicates;
    }
  }
  for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
    for (int i = 0; i < 4; ++i) ++c->vertex(i)->info().cells;
  }
  stats.vertices = num_vertices();
  stats.cells = num_cells();
  stats.seconds_triangulation = timer.Seconds();
  spdlog::info(
      "manifold: Delaunay of {} points + {} Steiner points ({} graded): {} cells in {:.2f} s",
      points.size(), steiner.size(), made.graded, stats.cells, stats.seconds_triangulation);

  // (2) Ray tracing and weighting.
  timer.Restart();
  camera_points_.clear();
  for (const ManifoldCamera& c : cameras_) camera_points_.push_back(ToPoint(c.center));
  for (size_t c = 0; c < cameras_.size(); ++c) {
    camera_cells_[c].valid = false;
    StartOf(static_cast<int>(c));
  }
  for (size_t i = 0; i < points.size(); ++i) {
    for (int32_t c : point_cameras_[i]) ray_index_->Add(c, static_cast<int32_t>(i), positions_[i]);
  }
  ray_index_->Flush();
  Progress progress("manifold: ray tracing", static_cast<int64_t>(ray_index_->size()));
  const auto count = [&](const Cell_handle& c, unsigned mask) { CountCrossing(c, mask); };
  // Walked straight from the index, in its order (no list of every ray: 12 bytes a ray).
  ray_index_->ForEachInDirectionOrder([&](const RayRef& ray) {
    stats.ray_cell_steps +=
        Walk(StartOf(ray.camera), camera_points_[ray.camera], vertex_of_point_[ray.point], count);
    ++stats.rays;
    progress.Update(stats.rays);
  });
  stats.seconds_ray_tracing = timer.Seconds();
  spdlog::info("manifold: traced {} rays ({} cell steps) in {:.2f} s ({:.0f} rays/s)", stats.rays,
               stats.ray_cell_steps, stats.seconds_ray_tracing,
               stats.seconds_ray_tracing > 0 ? stats.rays / stats.seconds_ray_tracing : 0.0);

  // (3) Growing.
  timer.Restart();
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    stats.free_cells += IsFree(c);
  }
  GrowFromHeaviest();
  stats.outside_cells = outside_count_;
  stats.free_cells_left_inside = CountFreeCellsInside();
  stats.seconds_growing = timer.Seconds();
  stats.manifold_tests = test_counts_.fast;
  stats.full_manifold_tests = test_counts_.full;
  stats.link_steps = test_counts_.link_steps;
  spdlog::info("manifold: grew O to {} of {} free cells in {:.2f} s", stats.outside_cells,
               stats.free_cells, stats.seconds_growing);
  if (options_.validate_each_step) {
    const std::string problem = Validate(true);
    if (!problem.empty()) throw InternalError("manifold invalid after build: " + problem);
  }
  return stats;
}

// ---------------------------------------------------------------------------------------------
// Incremental insertion

InsertionStats DelaunayManifold::Impl::Insert(const std::vector<RayPoint>& points) {
  MS_CHECK(built_) << "Insert before Build";
  InsertionStats stats;
  stats.requested = static_cast<int64_t>(points.size());
  for (size_t n = 0; n < points.size(); ++n) {
    if (!points[n].position.allFinite()) {
      throw InputError("new point " + std::to_string(n) + ": position is not finite");
    }
    for (int32_t c : points[n].cameras) {
      if (c < 0 || c >= static_cast<int32_t>(cameras_.size())) {
        throw InputError("new point " + std::to_string(n) + ": camera " + std::to_string(c) +
                         " out of range");
      }
    }
  }
  Timer timer;
  Progress progress("manifold: inserting points", stats.requested);
  // Cells created in this batch carry its number; their ray counts are rebuilt once at the
  // end (shrinking and the discard rule do not depend on weights, only growing does).
  const uint32_t batch = ++batch_;
  const int32_t first_new_id = static_cast<int32_t>(positions_.size());
  std::vector<Cell_handle> conflicts, around;
  std::vector<std::pair<CellKey, Cell_handle>> shrink_set;
  std::vector<Facet> boundary;
  std::vector<RayRef> candidates;
  // Per old ray (by its id in the ray index): the smallest parameter (0 at the camera, 1 at
  // the point) where it may enter a new cell; > 1: none.
  std::vector<float> ray_reach(ray_index_->size(), 2.0f);
  bool all_affected = false;  // every old ray from its camera on
  // Slack for the segment/box test: rounding in the box and the clipping, scene-relative.
  const double box_slack = 1e-9 * (box_max_ - box_min_).norm();
  Cell_handle hint;
  for (size_t n = 0; n < points.size(); ++n) {
    progress.Update(static_cast<int64_t>(n));
    const RayPoint& rp = points[n];
    if (!((rp.position.array() > box_min_.array()).all() &&
          (rp.position.array() < box_max_.array()).all())) {
      ++stats.discarded_outside;
      continue;
    }
    const Point p = ToPoint(rp.position);
    Locate_type type;
    int li, lj;
    const Cell_handle located = dt_.locate(p, type, li, lj, hint);
    if (type == Delaunay::VERTEX) {
      ++stats.discarded_duplicate;
      continue;
    }
    if (type == Delaunay::OUTSIDE_CONVEX_HULL || type == Delaunay::OUTSIDE_AFFINE_HULL) {
      ++stats.discarded_outside;
      continue;
    }
    conflicts.clear();
    boundary.clear();
    dt_.find_conflicts(p, located, std::back_inserter(boundary), std::back_inserter(conflicts));
    if (std::any_of(conflicts.begin(), conflicts.end(),
                    [&](const Cell_handle& c) { return dt_.is_infinite(c); })) {
      ++stats.discarded_outside;
      continue;
    }

    // Shrink: remove cells of E (D, then its neighbourhood) from O where the surface stays
    // manifold, until D has left O or nothing more can be removed.
    const uint32_t stamp = NextStamp();
    shrink_set.clear();
    const auto add_to_shrink_set = [&](const Cell_handle& c) {
      if (dt_.is_infinite(c) || c->info().stamp == stamp) return;
      c->info().stamp = stamp;
      if (c->info().outside) shrink_set.push_back({Key(c), c});
    };
    for (const Cell_handle& c : conflicts) add_to_shrink_set(c);
    const size_t num_in_d = shrink_set.size();
    if (num_in_d > 0) {
      for (const Cell_handle& c : conflicts) {
        if (options_.shrink_neighbourhood == 0) {
          for (int i = 0; i < 4; ++i) add_to_shrink_set(c->neighbor(i));
        } else {
          for (int i = 0; i < 4; ++i) {
            around.clear();
            dt_.incident_cells(c->vertex(i), std::back_inserter(around));
            for (const Cell_handle& a : around) add_to_shrink_set(a);
          }
        }
      }
      const auto by_key = [](const auto& x, const auto& y) { return x.first < y.first; };
      std::sort(shrink_set.begin(), shrink_set.begin() + num_in_d, by_key);
      std::sort(shrink_set.begin() + num_in_d, shrink_set.end(), by_key);
    }
    size_t d_in_o = num_in_d;
    for (bool changed = true; changed && d_in_o > 0;) {
      changed = false;
      for (size_t k = 0; k < shrink_set.size() && d_in_o > 0; ++k) {
        const Cell_handle& c = shrink_set[k].second;
        if (c->info().outside && FlipKeepsManifold(c)) {
          SetOutside(c, false);
          for (int i = 0; i < 4; ++i) c->vertex(i)->info().changed = batch;
          ++stats.shrunk_cells;
          changed = true;
          if (k < num_in_d) --d_in_o;
        }
      }
    }
    if (d_in_o > 0) {
      // Discarded (the paper's rule); the cells shrunk for it stay out of O until regrowing.
      ++stats.discarded_conflict;
      hint = located;
      continue;
    }

    // Old rays that may cross the hole (conservative box query), for the recount below.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (const Cell_handle& c : conflicts) {
      if (c->info().has_camera) {
        for (CameraStart& start : camera_cells_) {
          if (start.valid && start.cell == c) start.valid = false;
        }
      }
      for (int i = 0; i < 4; ++i) {
        const Point& q = c->vertex(i)->point();
        const Eigen::Vector3d x(q.x(), q.y(), q.z());
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
      }
    }
    // A candidate costs about what 1/20 of a whole re-walk does: past 20 candidates per ray,
    // (large conflict regions: the box-only Steiner grid's long cells) every ray is walked.
    if (!all_affected &&
        stats.candidate_rays > 20 * static_cast<int64_t>(ray_index_->size())) {
      all_affected = true;
      std::fill(ray_reach.begin(), ray_reach.end(), 0.0f);
    }
    candidates.clear();
    if (!all_affected) ray_index_->Query(lo, hi, &candidates);
    stats.candidate_rays += static_cast<int64_t>(candidates.size());
    const Eigen::Vector3d slack = Eigen::Vector3d::Constant(box_slack);
    for (const RayRef& ray : candidates) {
      double entry;
      if (SegmentMeetsBox(cameras_[ray.camera].center, positions_[ray.point], lo - slack,
                          hi + slack, &entry)) {
        float& reach = ray_reach[ray.id];
        // Rounded down (float), so the walk starts no later than the box.
        reach = std::min(reach, static_cast<float>(entry) - 1e-6f);
      }
    }

    for (const Cell_handle& c : conflicts) {
      for (int i = 0; i < 4; ++i) --c->vertex(i)->info().cells;
    }
    const Vertex_handle v = dt_.insert_in_hole(p, conflicts.begin(), conflicts.end(),
                                               boundary.front().first, boundary.front().second);
    v->info() = VertexInfo{static_cast<int32_t>(positions_.size()), 0, 0, 0, batch};
    around.clear();
    dt_.incident_cells(v, std::back_inserter(around));
    for (const Cell_handle& c : around) {
      c->info() = CellInfo{};
      c->info().born = batch;
      for (int i = 0; i < 4; ++i) {
        ++c->vertex(i)->info().cells;
        c->vertex(i)->info().changed = batch;
      }
    }
    positions_.push_back(rp.position);
    std::vector<int32_t> cams = rp.cameras;
    std::sort(cams.begin(), cams.end());
    cams.erase(std::unique(cams.begin(), cams.end()), cams.end());
    point_cameras_.push_back(std::move(cams));
    vertex_of_point_.push_back(v);
    ++stats.inserted;
    hint = v->cell();
  }

  // Exact ray counts for the cells born in this batch: every old ray that may cross one is
  // walked once and counted on those cells only (the others keep their counts: their geometry
  // did not change); the new points' rays are walked and counted everywhere.
  // The rays are walked in the index's order (which keeps cells in cache); the new points'
  // rays join the index only afterwards.
  const auto is_new = [&](const Cell_handle& c) { return c->info().born == batch; };
  const auto count_new_cells = [&](const Cell_handle& c, unsigned mask) {
    if (is_new(c)) CountCrossing(c, mask);
  };
  ray_index_->ForEachInDirectionOrder([&](const RayRef& ray) {
    const float reach = ray_reach[ray.id];
    if (reach > 1.0f) return;
    const Vertex_handle target = vertex_of_point_[ray.point];
    // Only the part of the ray from its first hole box on can cross a new cell: walk that
    // part backwards from the point; where that is degenerate, the whole ray forwards.
    if (reach <= 0 || !WalkBack(camera_points_[ray.camera], target, reach, is_new, count_new_cells,
                                &stats.rewalk_steps)) {
      stats.rewalk_steps +=
          Walk(StartOf(ray.camera), camera_points_[ray.camera], target, count_new_cells);
    }
    ++stats.rewalked_rays;
  });
  for (int32_t id = first_new_id; id < static_cast<int32_t>(positions_.size()); ++id) {
    const Vertex_handle target = vertex_of_point_[id];
    const auto count = [&](const Cell_handle& c, unsigned mask) { CountCrossing(c, mask); };
    for (int32_t c : point_cameras_[id]) {
      Walk(StartOf(c), camera_points_[c], target, count);
      ray_index_->Add(c, id, positions_[id]);
      ++stats.new_rays;
    }
  }
  ray_index_->Flush();
  stats.seconds_insertion = timer.Seconds();

  // Regrow from the cells on the boundary of O that the batch may have changed: a cell none of
  // whose vertices touches a new or shrunk cell has the weight and neighbourhood it had when
  // the last growing refused it.
  timer.Restart();
  if (stats.inserted > 0 || stats.shrunk_cells > 0) {  // otherwise nothing changed
    Grow(BoundarySeeds(batch));
    if (outside_count_ == 0) GrowFromHeaviest();
  }
  stats.outside_cells = outside_count_;
  stats.seconds_growing = timer.Seconds();
  spdlog::info(
      "manifold: {} new points: {} inserted, {} discarded (conflict {}, duplicate {}, outside "
      "{}), {} cells shrunk, {} rays re-walked; {:.2f} s inserting, {:.2f} s regrowing",
      stats.requested, stats.inserted,
      stats.discarded_conflict + stats.discarded_duplicate + stats.discarded_outside,
      stats.discarded_conflict, stats.discarded_duplicate, stats.discarded_outside,
      stats.shrunk_cells, stats.rewalked_rays, stats.seconds_insertion, stats.seconds_growing);
  if (options_.validate_each_step) {
    const std::string problem = Validate(true);
    if (!problem.empty()) throw InternalError("manifold invalid after insertion: " + problem);
  }
  return stats;
}

// ---------------------------------------------------------------------------------------------
// Surface extraction and validation

Mesh DelaunayManifold::Impl::ExtractSurface(SurfaceInfo* info) const {
  std::vector<std::array<int32_t, 3>> faces;  // by vertex id
  std::unordered_map<int32_t, Vertex_handle> used;
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    if (!c->info().outside) continue;
    for (int i = 0; i < 4; ++i) {
      if (InO(c->neighbor(i))) continue;
      // This vertex order makes the normal point into c, i.e. towards O (free space).
      std::array<int32_t, 3> face;
      for (int j = 0; j < 3; ++j) {
        const Vertex_handle v = c->vertex(Delaunay::vertex_triple_index(i, j));
        face[j] = v->info().id;
        used.emplace(face[j], v);
      }
      // Rotate so the smallest id leads (keeps orientation), for a canonical order.
      std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
      faces.push_back(face);
    }
  }
  std::vector<int32_t> ids;
  ids.reserve(used.size());
  for (const auto& entry : used) ids.push_back(entry.first);
  std::sort(ids.begin(), ids.end());
  std::unordered_map<int32_t, int32_t> index_of;
  Mesh mesh;
  mesh.vertices.reserve(ids.size());
  for (int32_t id : ids) {
    const Point& p = used[id]->point();
    index_of[id] = static_cast<int32_t>(mesh.vertices.size());
    mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  std::sort(faces.begin(), faces.end());
  mesh.faces.reserve(faces.size());
  for (const auto& f : faces) mesh.faces.push_back({index_of[f[0]], index_of[f[1]], index_of[f[2]]});
  if (info != nullptr) {
    info->vertex_ids = ids;
    info->steiner_vertices = std::count_if(ids.begin(), ids.end(), [](int32_t id) { return id < 0; });
  }
  return mesh;
}

std::string DelaunayManifold::Impl::Validate(bool check_weights) const {
  std::ostringstream problems;
  if (!dt_.is_valid(false)) problems << "CGAL triangulation invalid; ";
  std::unordered_map<const void*, int32_t> outside_cells, cells_around, surface_faces;
  int64_t outside = 0;
  for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
    for (int i = 0; i < 4; ++i) ++cells_around[&*c->vertex(i)];
    if (!c->info().outside) continue;
    for (int i = 0; i < 4; ++i) {
      if (InO(c->neighbor(i))) continue;
      for (int j = 0; j < 4; ++j) {
        if (j != i) ++surface_faces[&*c->vertex(j)];
      }
    }
    if (dt_.is_infinite(c)) {
      problems << "an infinite cell is in O; ";
      continue;
    }
    ++outside;
    for (int i = 0; i < 4; ++i) ++outside_cells[&*c->vertex(i)];
  }
  if (outside != outside_count_) {
    problems << "|O| is " << outside << " but bookkeeping says " << outside_count_ << "; ";
  }
  int64_t irregular = 0, bad_counts = 0;
  for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end(); ++v) {
    const auto it = outside_cells.find(&*v);
    const int32_t expected = it == outside_cells.end() ? 0 : it->second;
    if (v->info().outside_cells != expected) ++bad_counts;
    if (v->info().cells != cells_around[&*v]) ++bad_counts;
    if (v->info().surface_faces != surface_faces[&*v]) ++bad_counts;
    if (!VertexRegular(v, Cell_handle())) ++irregular;
  }
  if (bad_counts > 0) problems << bad_counts << " vertices with a wrong count of cells in O; ";
  if (irregular > 0) problems << irregular << " vertices are not regular (surface not manifold); ";
  if (check_weights) {
    std::unordered_map<const void*, std::array<int32_t, 5>> recount;  // crossings, spread[4]
    auto* self = const_cast<Impl*>(this);
    for (size_t i = 0; i < positions_.size(); ++i) {
      const Vertex_handle target_vertex = vertex_of_point_[i];
      const auto count = [&](const Cell_handle& c, unsigned mask) {
        auto& entry = recount.try_emplace(&*c, std::array<int32_t, 5>{0, 0, 0, 0, 0}).first->second;
        ++entry[0];
        if (options_.w2_rule == W2Rule::kAllFaces) mask = 0xF;
        for (int k = 0; k < 4; ++k) entry[1 + k] += (mask >> k) & 1;
      };
      for (int32_t c : point_cameras_[i]) {
        CameraStart start;
        start.cell = dt_.locate(camera_points_[c], start.type, start.li, start.lj);
        start.valid = true;
        self->Walk(start, camera_points_[c], target_vertex, count);
      }
    }
    int64_t wrong = 0;
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
      const auto it = recount.find(&*c);
      const std::array<int32_t, 5> expected =
          it == recount.end() ? std::array<int32_t, 5>{0, 0, 0, 0, 0} : it->second;
      const CellInfo& info = c->info();
      if (info.crossings != expected[0] || info.spread[0] != expected[1] ||
          info.spread[1] != expected[2] || info.spread[2] != expected[3] ||
          info.spread[3] != expected[4]) {
        ++wrong;
      }
    }
    if (wrong > 0) problems << wrong << " cells whose ray count differs from a recount; ";
  }
  return problems.str();
}

// ---------------------------------------------------------------------------------------------

Mesh SurfaceWithoutSteinerFaces(const Mesh& mesh, const SurfaceInfo& info) {
  MS_CHECK(info.vertex_ids.size() == mesh.vertices.size()) << "SurfaceInfo of another mesh";
  Mesh surface;
  surface.vertices = mesh.vertices;
  surface.vertex_colors = mesh.vertex_colors;
  for (const auto& f : mesh.faces) {
    if (info.vertex_ids[f[0]] >= 0 && info.vertex_ids[f[1]] >= 0 && info.vertex_ids[f[2]] >= 0) {
      surface.faces.push_back(f);
    }
  }
  surface.RemoveUnreferencedVertices();
  return surface;
}

DelaunayManifold::DelaunayManifold(std::vector<ManifoldCamera> cameras,
                                   const ManifoldOptions& options)
    : impl_(std::make_unique<Impl>(std::move(cameras), options)) {}
DelaunayManifold::~DelaunayManifold() = default;
BuildStats DelaunayManifold::Build(const std::vector<RayPoint>& points) { return impl_->Build(points); }
InsertionStats DelaunayManifold::Insert(const std::vector<RayPoint>& points) {
  return impl_->Insert(points);
}
Mesh DelaunayManifold::ExtractSurface(SurfaceInfo* info) const { return impl_->ExtractSurface(info); }
std::string DelaunayManifold::Validate(bool check_weights) const {
  return impl_->Validate(check_weights);
}
int64_t DelaunayManifold::num_points() const { return impl_->num_points(); }
int64_t DelaunayManifold::num_vertices() const { return impl_->num_vertices(); }
int64_t DelaunayManifold::num_cells() const { return impl_->num_cells(); }
int64_t DelaunayManifold::num_outside_cells() const { return impl_->num_outside_cells(); }
int64_t DelaunayManifold::num_free_cells_inside() const { return impl_->CountFreeCellsInside(); }
size_t DelaunayManifold::MemoryBytes() const { return impl_->MemoryBytes(); }

}  // namespace ms

// ---------------------------------------------------------------------------------------------
// Test hooks (manifold/manifold_internal.h)

namespace ms::manifold_internal {
namespace {

using PlainDelaunay = Delaunay;

PlainDelaunay Triangulate(const std::vector<Eigen::Vector3d>& points) {
  std::vector<std::pair<Point, VertexInfo>> vertices;
  for (size_t i = 0; i < points.size(); ++i) {
    vertices.push_back({ToPoint(points[i]), {static_cast<int32_t>(i), 0, 0, 0, 0}});
  }
  PlainDelaunay dt(vertices.begin(), vertices.end());
  return dt;
}

CellVertices SortedIds(const Cell_handle& c) {
  CellVertices key;
  for (int i = 0; i < 4; ++i) key[i] = c->vertex(i)->info().id;
  std::sort(key.begin(), key.end());
  return key;
}

}  // namespace

bool SegmentCrossesTetrahedron(std::array<Eigen::Vector3d, 4> tet, const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b) {
  std::vector<Eigen::Vector3d> points(tet.begin(), tet.end());
  PlainDelaunay dt = Triangulate(points);
  MS_CHECK(dt.number_of_finite_cells() == 1) << "degenerate tetrahedron";
  return SegmentCrossesCell(dt.finite_cells_begin(), ToPoint(a), ToPoint(b));
}

std::vector<CellVertices> DelaunayCells(const std::vector<Eigen::Vector3d>& points) {
  PlainDelaunay dt = Triangulate(points);
  std::vector<CellVertices> cells;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) cells.push_back(SortedIds(c));
  std::sort(cells.begin(), cells.end());
  return cells;
}

}  // namespace ms::manifold_internal

namespace ms {

// Friend of DelaunayManifold::Impl for the hooks that need its internals.
struct ManifoldTestAccess {
  static bool IsVertexRegular(const std::vector<Eigen::Vector3d>& points,
                              const std::vector<manifold_internal::CellVertices>& outside,
                              int32_t v) {
    DelaunayManifold::Impl impl({}, ManifoldOptions{});
    impl.dt_ = manifold_internal::Triangulate(points);
    Vertex_handle vertex;
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      if (std::binary_search(outside.begin(), outside.end(), manifold_internal::SortedIds(c))) {
        impl.SetOutside(c, true);
      }
    }
    for (auto it = impl.dt_.finite_vertices_begin(); it != impl.dt_.finite_vertices_end(); ++it) {
      if (it->info().id == v) vertex = it;
    }
    MS_CHECK(vertex != Vertex_handle()) << "no vertex " << v;
    return impl.VertexRegular(vertex, Cell_handle());
  }

  // Random O sets (random flips that keep the surface manifold), then both regularity tests
  // on every vertex of random cells: they must agree.
  static int64_t RegularityTestMismatches(const std::vector<Eigen::Vector3d>& points,
                                          uint32_t seed, int64_t* checked) {
    DelaunayManifold::Impl impl({}, ManifoldOptions{});
    std::vector<RayPoint> rays(points.size());
    for (size_t i = 0; i < points.size(); ++i) rays[i].position = points[i];
    impl.Build(rays);
    std::vector<Cell_handle> cells;
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      cells.push_back(c);
    }
    uint64_t state = seed * 2654435761u + 1;
    const auto next = [&]() {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<size_t>(state >> 33);
    };
    int64_t mismatches = 0;
    *checked = 0;
    for (int step = 0; step < 4000; ++step) {
      const Cell_handle t = cells[next() % cells.size()];
      bool fast = true, full = true;
      for (int i = 0; i < 4; ++i) {
        const bool a = impl.VertexRegularAfterFlip(t->vertex(i), t);
        const bool b = impl.VertexRegular(t->vertex(i), t);
        mismatches += a != b;
        ++*checked;
        fast &= a;
        full &= b;
      }
      if (fast && full) impl.SetOutside(t, !t->info().outside);
    }
    return mismatches;
  }

  static void CrossedCells(const std::vector<Eigen::Vector3d>& points,
                           const Eigen::Vector3d& camera, int32_t target,
                           std::vector<manifold_internal::CellVertices>* walked,
                           std::vector<manifold_internal::CellVertices>* brute_force) {
    ManifoldCamera cam;
    cam.center = camera;
    DelaunayManifold::Impl impl({cam}, ManifoldOptions{});
    std::vector<RayPoint> rays(points.size());
    for (size_t i = 0; i < points.size(); ++i) rays[i].position = points[i];
    impl.Build(rays);
    const Point a = impl.camera_points_[0];
    const Point b = impl.vertex_of_point_[target]->point();
    walked->clear();
    impl.Walk(impl.StartOf(0), a, impl.vertex_of_point_[target],
              [&](const Cell_handle& c, unsigned) { walked->push_back(manifold_internal::SortedIds(c)); });
    brute_force->clear();
    for (auto c = impl.dt_.finite_cells_begin(); c != impl.dt_.finite_cells_end(); ++c) {
      if (SegmentCrossesCell(c, a, b)) brute_force->push_back(manifold_internal::SortedIds(c));
    }
    std::sort(walked->begin(), walked->end());
    std::sort(brute_force->begin(), brute_force->end());
  }
};

namespace manifold_internal {
int64_t RegularityTestMismatches(const std::vector<Eigen::Vector3d>& points, uint32_t seed,
                                 int64_t* checked) {
  return ManifoldTestAccess::RegularityTestMismatches(points, seed, checked);
}
bool IsVertexRegular(const std::vector<Eigen::Vector3d>& points,
                     const std::vector<CellVertices>& outside, int32_t v) {
  std::vector<CellVertices> sorted = outside;
  std::sort(sorted.begin(), sorted.end());
  return ManifoldTestAccess::IsVertexRegular(points, sorted, v);
}
void CrossedCells(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& camera,
                  int32_t target, std::vector<CellVertices>* walked,
                  std::vector<CellVertices>* brute_force) {
  ManifoldTestAccess::CrossedCells(points, camera, target, walked, brute_force);
}
}  // namespace manifold_internal

}  // namespace ms
