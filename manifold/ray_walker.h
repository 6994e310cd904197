// Walks viewing rays (open segments camera -> point) through the triangulation and reports
// every cell they cross, with the faces the ray spreads w2 across (docs/design/manifold.md, "Ray
// tracing"): forwards from the camera (Walk), backwards from the point (WalkBack, for the
// insertion's recount), and an exhaustive fallback for degenerate segments. Internal to
// manifold/.
//
// The walker reads the triangulation's structure and writes only CellInfo::has_camera (when it
// locates a camera) and the visit marks of a walk. Those are CellInfo::stamp for the plain walks
// (StampMarks); the *With walks take the marks and scratch buffers as arguments, so that several
// threads can walk at once with a LocalMarks and a WalkScratch each (manifold/parallel_walks.h).
// It owns the stamp counter, its own scratch buffers and the cameras' start cells.
//
// The walks are templates on the visitor, called once per crossed cell; they are defined at the
// bottom of this header so that each caller's visitor is inlined into the walk loop.
#pragma once

#include <CGAL/intersections.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <unordered_set>
#include <utility>
#include <vector>

#include "base/check.h"
#include "manifold/cell_predicates.h"
#include "manifold/triangulation.h"

namespace ms::manifold_detail {

class RayWalker;

// A walk's visit marks in the cells themselves (CellInfo::stamp): one walk at a time.
class StampMarks {
 public:
  // Walks with these marks run one at a time: CGAL's incident_cells, which marks cells as it
  // goes, may serve them.
  static constexpr bool kConcurrent = false;
  explicit StampMarks(RayWalker* walker) : walker_(walker) {}
  inline void Begin();  // forgets the marks of the walk before
  void Mark(const Cell_handle& c) { c->info().stamp = stamp_; }
  bool Marked(const Cell_handle& c) const { return c->info().stamp == stamp_; }

 private:
  RayWalker* walker_;
  uint32_t stamp_ = 0;
};

// A walk's visit marks in a set of its own (open addressing on the cell's address), which
// leaves the cells untouched: one per thread walking.
class LocalMarks {
 public:
  // Walks with these marks may run at once: stars are found without CGAL's cell marks.
  static constexpr bool kConcurrent = true;
  LocalMarks() : slots_(kInitialSlots, nullptr) {}
  void Begin() {
    for (uint32_t s : used_) slots_[s] = nullptr;
    used_.clear();
  }
  void Mark(const Cell_handle& c) {
    if (2 * (used_.size() + 1) > slots_.size()) Grow();
    const void* key = &*c;
    uint32_t s = SlotOf(key);
    while (slots_[s] != nullptr) {
      if (slots_[s] == key) return;
      s = (s + 1) & (slots_.size() - 1);
    }
    slots_[s] = key;
    used_.push_back(s);
  }
  bool Marked(const Cell_handle& c) const {
    const void* key = &*c;
    for (uint32_t s = SlotOf(key); slots_[s] != nullptr; s = (s + 1) & (slots_.size() - 1)) {
      if (slots_[s] == key) return true;
    }
    return false;
  }

 private:
  static constexpr size_t kInitialSlots = 1024;  // a power of two; most walks cross < 100 cells
  uint32_t SlotOf(const void* key) const {
    // Cells are at least 64 bytes apart: the low bits carry nothing.
    const uint64_t h = (reinterpret_cast<uintptr_t>(key) >> 6) * 0x9E3779B97F4A7C15ull;
    return static_cast<uint32_t>(h >> 32) & (slots_.size() - 1);
  }
  void Grow() {
    std::vector<const void*> keys;
    for (uint32_t s : used_) keys.push_back(slots_[s]);
    slots_.assign(2 * slots_.size(), nullptr);
    used_.clear();
    for (const void* key : keys) {
      uint32_t s = SlotOf(key);
      while (slots_[s] != nullptr) s = (s + 1) & (slots_.size() - 1);
      slots_[s] = key;
      used_.push_back(s);
    }
  }
  std::vector<const void*> slots_;
  std::vector<uint32_t> used_;  // the filled slots, to clear
};

// The buffers a walk reuses: one per thread walking.
struct WalkScratch {
  std::vector<Cell_handle> cells;                         // by Walk
  std::vector<std::pair<Cell_handle, unsigned>> crossed;  // by WalkBack
};

// Where a camera's rays start: the simplex of the triangulation that holds the camera centre
// (CGAL locate).
struct CameraStart {
  bool valid = false;
  Cell_handle cell;
  Locate_type type = Delaunay::CELL;
  int li = 0, lj = 0;
};

class RayWalker {
 public:
  // `dt` must outlive the walker.
  RayWalker(const Delaunay& dt, size_t num_cameras) : dt_(dt), camera_cells_(num_cameras) {}

  // Locates every camera centre (after the triangulation is built) and marks the start cells.
  void LocateCameras(const std::vector<Eigen::Vector3d>& centers);
  const Point& camera_point(int camera) const { return camera_points_[camera]; }

  // The start of `camera`'s rays, located again if an insertion destroyed its cell.
  const CameraStart& StartOf(int camera);
  // Locates `camera` afresh, caching and marking nothing (for checks).
  CameraStart Locate(int camera) const;
  // Forgets every start in c, a cell about to be destroyed (one with info().has_camera).
  void ForgetStartsIn(const Cell_handle& c);

  // A new visit stamp. Every pass that marks cells shares CellInfo::stamp, so every one takes
  // its stamps here (also the insertion's shrink set).
  uint32_t NextStamp();

  // Calls visit(cell, mask) for every cell crossed by the open segment a -> target (a: the
  // camera at `start`); bit i of mask: the ray spreads w2 across face i (the camera is beyond
  // it). Returns the cells stepped through.
  template <typename Visit>
  int64_t Walk(const CameraStart& start, const Point& a, const Vertex_handle& target,
               Visit&& visit) {
    StampMarks marks(this);
    return WalkWith(start, a, target, marks, scratch_, visit);
  }
  // The same from camera `camera`'s start.
  template <typename Visit>
  int64_t WalkFromCamera(int camera, const Vertex_handle& target, Visit&& visit) {
    return Walk(StartOf(camera), camera_points_[camera], target, visit);
  }
  // Walk with the caller's marks and buffers; reads the triangulation only (safe on several
  // threads at once with LocalMarks).
  template <typename Marks, typename Visit>
  int64_t WalkWith(const CameraStart& start, const Point& a, const Vertex_handle& target,
                   Marks& marks, WalkScratch& scratch, Visit&& visit) const {
    return WalkSegmentWith(start, a, target->point(), &target, marks, scratch, visit);
  }
  // The same for a segment a -> b that ends at any point b of the triangulation, a vertex or
  // not (a tile walking a ray to a point it does not hold).
  template <typename Marks, typename Visit>
  int64_t WalkToPointWith(const CameraStart& start, const Point& a, const Point& b, Marks& marks,
                          WalkScratch& scratch, Visit&& visit) const {
    return WalkSegmentWith(start, a, b, nullptr, marks, scratch, visit);
  }
  // The same from camera `camera`'s start, which must be located (LocateStarts).
  template <typename Marks, typename Visit>
  int64_t WalkFromCameraWith(int camera, const Vertex_handle& target, Marks& marks,
                             WalkScratch& scratch, Visit&& visit) const {
    const CameraStart& start = camera_cells_[camera];
    MS_CHECK(start.valid) << "camera " << camera << " walked from before it is located";
    return WalkWith(start, camera_points_[camera], target, marks, scratch, visit);
  }
  // Locates again every camera whose start an insertion destroyed, so that the *With walks can
  // start from any camera.
  void LocateStarts();

  // Walks the open segment a -> target backwards from the target and calls visit(cell, mask)
  // (masks as Walk's) for the cells it crosses at parameters >= reach (0 at a, 1 at the
  // target) for which wants(cell) holds, stopping at the first cell lying wholly before reach.
  // Returns false, having visited nothing, where the segment runs along a face or an edge:
  // then walk forwards. *steps is increased by the cells stepped through.
  template <typename Wants, typename Visit>
  bool WalkBack(const Point& a, const Vertex_handle& target, double reach, Wants&& wants,
                Visit&& visit, int64_t* steps) {
    StampMarks marks(this);
    return WalkBackWith(a, target, reach, wants, marks, scratch_, visit, steps);
  }
  // WalkBack with the caller's marks and buffers (as WalkWith).
  template <typename Wants, typename Marks, typename Visit>
  bool WalkBackWith(const Point& a, const Vertex_handle& target, double reach, Wants&& wants,
                    Marks& marks, WalkScratch& scratch, Visit&& visit, int64_t* steps) const;

  // The cells around a camera located on a facet, an edge or a vertex (its one cell otherwise).
  // concurrent: safe while other threads walk (IncidentCells), in another order.
  std::vector<Cell_handle> StartCandidates(const CameraStart& start, bool concurrent = false) const;

 private:
  // The walks forwards: to the vertex *end_vertex at b, or to the point b (end_vertex null).
  template <typename Marks, typename Visit>
  int64_t WalkSegmentWith(const CameraStart& start, const Point& a, const Point& b,
                          const Vertex_handle* end_vertex, Marks& marks, WalkScratch& scratch,
                          Visit&& visit) const;
  // Exhaustive enumeration for degenerate segments (see the definition).
  template <typename Marks, typename Visit>
  void WalkFallback(Cell_handle from, const Point& a, const Point& b, Marks& marks,
                    Visit& visit) const;
  // The cells around v, appended to *cells. CGAL's incident_cells marks the cells it finds
  // (tds_data) and clears them after: two threads at once would break each other's search.
  void IncidentCells(const Vertex_handle& v, bool concurrent,
                     std::vector<Cell_handle>* cells) const {
    if (concurrent) {
      dt_.incident_cells_threadsafe(v, std::back_inserter(*cells));
    } else {
      dt_.incident_cells(v, std::back_inserter(*cells));
    }
  }
  const Delaunay& dt_;
  std::vector<Point> camera_points_;
  std::vector<CameraStart> camera_cells_;
  uint32_t stamp_ = 0;
  bool starts_located_ = false;  // every start valid (LocateStarts has nothing to do)
  WalkScratch scratch_;          // of the plain walks
};

inline void StampMarks::Begin() { stamp_ = walker_->NextStamp(); }

// ---------------------------------------------------------------------------------------------
// The walks (templates)

// Asks for the cache lines of a cell (vertices, neighbours and info span two).
inline void PrefetchCell(const Cell_handle& c) {
  const char* bytes = reinterpret_cast<const char*>(&*c);
  __builtin_prefetch(bytes);
  __builtin_prefetch(bytes + 64);
}

template <typename Marks, typename Visit>
int64_t RayWalker::WalkSegmentWith(const CameraStart& start, const Point& a, const Point& b,
                                   const Vertex_handle* end_vertex, Marks& marks,
                                   WalkScratch& scratch, Visit&& visit) const {
  marks.Begin();
  int64_t steps = 0;
  Cell_handle current;
  if (start.type == Delaunay::CELL) {
    current = start.cell;  // the camera is strictly inside: the segment starts in this cell
  } else {
    const std::vector<Cell_handle> candidates = StartCandidates(start, Marks::kConcurrent);
    for (const Cell_handle& c : candidates) {
      if (!dt_.is_infinite(c) && SegmentCrossesCell(c, a, b)) {
        current = c;
        break;
      }
    }
    if (current == Cell_handle()) {
      // The segment leaves the camera along a face or edge: enumerate exhaustively.
      WalkFallback(candidates.front(), a, b, marks, visit);
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
    marks.Mark(current);
    ++steps;
    Cell_handle next;
    int exit = -1;
    // A crossed cell incident to the end vertex is the last one (convexity).
    const bool last = end_vertex != nullptr && current->has_vertex(*end_vertex);
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
      // The line leaves through `exit`; an end point that is not beyond it ends the segment in
      // this cell, or on its boundary, where the open segment crosses nothing further.
      if (end_vertex == nullptr && FaceSide(current, exit, b) != CGAL::NEGATIVE) break;
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
        std::vector<Cell_handle>& around = scratch.cells;
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
          IncidentCells(current->vertex(vertex), Marks::kConcurrent, &around);
        }
        for (const Cell_handle& c : around) {
          if (!marks.Marked(c) && !dt_.is_infinite(c) && SegmentCrossesCell(c, a, b)) {
            next = c;
            break;
          }
        }
        if (next == Cell_handle()) {
          // Degenerate: the segment runs inside a face or along an edge for a while.
          WalkFallback(current, a, b, marks, visit);
          return steps;
        }
        entry = -1;
        current = next;
        continue;
      }
    }
    next = current->neighbor(exit);
    MS_CHECK(!dt_.is_infinite(next)) << "viewing ray leaves the triangulation";
    if (marks.Marked(next)) {
      WalkFallback(current, a, b, marks, visit);
      return steps;
    }
    entry = next->index(current);
    current = next;
  }
  return steps;
}

template <typename Wants, typename Marks, typename Visit>
bool RayWalker::WalkBackWith(const Point& a, const Vertex_handle& target, double reach,
                             Wants&& wants, Marks& marks, WalkScratch& scratch, Visit&& visit,
                             int64_t* steps) const {
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
  marks.Begin();
  for (int star_steps = 0;; ++star_steps) {
    if (dt_.is_infinite(current) || marks.Marked(current) || star_steps > 64) {
      return false;  // not expected inside the Steiner box; the forward walk is exact
    }
    marks.Mark(current);
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

  marks.Begin();
  std::vector<std::pair<Cell_handle, unsigned>>& crossed = scratch.crossed;
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
    marks.Mark(current);
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
      if (num_ties > 1) return false;         // leaves through an edge or a vertex
    }
    if (before_reach_except(exit)) break;
    const Cell_handle next = current->neighbor(exit);
    if (dt_.is_infinite(next) || marks.Marked(next)) return false;
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
template <typename Marks, typename Visit>
void RayWalker::WalkFallback(Cell_handle from, const Point& a, const Point& b, Marks& marks,
                             Visit& visit) const {
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
    if (!marks.Marked(c) && SegmentCrossesCell(c, a, b, sides)) {
      marks.Mark(c);
      visit(c, CameraSideMask(sides.a));
    }
    for (int i = 0; i < 4; ++i) {
      around.clear();
      IncidentCells(c->vertex(i), Marks::kConcurrent, &around);
      for (const Cell_handle& n : around) {
        if (seen.insert(&*n).second) stack.push_back(n);
      }
    }
  }
}

}  // namespace ms::manifold_detail
