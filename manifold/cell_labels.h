// The labels and weights of the cells (paper section 2.1, docs/design/manifold.md): the visibility
// weight of a cell from the rays counted on it and its neighbours, whether it is free space,
// and the set O of outside cells with the per-vertex counts that keep the manifold tests
// (regularity.h) local. Internal to manifold/.
//
// Holds no cell data itself: that lives in CellInfo and VertexInfo (triangulation.h); the
// triangulation's structure is only read. Inline: growing and the ray walks call these per cell.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>

#include "base/check.h"
#include "manifold/manifold_options.h"
#include "manifold/triangulation.h"

namespace ms::manifold_detail {

// In O (an infinite cell never is).
inline bool InO(const Delaunay& dt, const Cell_handle& c) {
  return !dt.is_infinite(c) && c->info().outside;
}

class CellLabels {
 public:
  // `dt` must outlive this object; the weight parameters of `options` are copied.
  CellLabels(const Delaunay& dt, const ManifoldOptions& options)
      : dt_(dt),
        w1_(options.w1),
        w2_(options.w2),
        free_threshold_(options.free_threshold),
        behind_ratio_(options.behind_ratio),
        w2_rule_(options.w2_rule) {}

  // Graded Steiner points in use (decided by Build): cells of Steiner points only are free.
  void set_graded(bool graded) { graded_ = graded; }
  int64_t outside_count() const { return outside_count_; }

  bool InO(const Cell_handle& c) const { return manifold_detail::InO(dt_, c); }

  // w1 per ray crossing c, plus w2 per ray crossing a face neighbour n that spreads across
  // the face n shares with c.
  double Weight(const Cell_handle& c) const {
    int64_t neighbours = 0;
    for (int i = 0; i < 4; ++i) {
      const Cell_handle n = c->neighbor(i);
      neighbours += Spread(n, n->index(c));
    }
    return w1_ * c->info().crossings + w2_ * static_cast<double>(neighbours);
  }

  // The rays crossing c that spread w2 across its face i.
  int64_t Spread(const Cell_handle& c, int i) const {
    const uint16_t packed = c->info().spread[i];
    if (packed != CellInfo::kSpreadOverflow) return packed;
    return overflow_.at(&*c)[i];
  }

  bool IsFree(const Cell_handle& c) const {
    if (dt_.is_infinite(c) || c->info().frozen) return false;
    // With graded Steiner points, a cell of Steiner points only is empty space (no input point
    // in its circumsphere): free without rays, so the free space stays one region around the
    // cameras instead of narrow cones that growing cannot carve (docs/design/manifold.md).
    if (graded_ && c->vertex(0)->info().id < 0 && c->vertex(1)->info().id < 0 &&
        c->vertex(2)->info().id < 0 && c->vertex(3)->info().id < 0) {
      return true;
    }
    // The free-space cut decided the cells that existed when it ran (--manifold.visibility cut).
    if (!cut_.empty()) {
      const auto it = cut_.find(&*c);
      if (it != cut_.end()) return it->second;
    }
    // Rays that end just in front of a cell are evidence of matter there: a cell that more of
    // them enter past their points than cross it stays matter (behind_ratio).
    if (behind_ratio_ > 0 && c->info().crossings < behind_ratio_ * Behind(c)) return false;
    return Weight(c) >= free_threshold_;
  }

  // Free space that has not joined O: what growing, pockets and star completion may add.
  bool FreeOutsideO(const Cell_handle& c) const { return !c->info().outside && IsFree(c); }

  // Flips so far: a vertex whose VertexInfo::relabelled is at most a value read earlier has
  // seen no cell around it flip since.
  uint32_t relabels() const { return relabels_; }

  // Counts one ray crossing c; bit i of `spread_mask` says it spreads w2 across face i.
  void CountCrossing(const Cell_handle& c, unsigned spread_mask) {
    CellInfo& info = c->info();
    ++info.crossings;
    spread_mask = SpreadMask(spread_mask);
    for (int i = 0; i < 4; ++i) {
      if (((spread_mask >> i) & 1) == 0) continue;
      uint16_t& packed = info.spread[i];
      if (packed < CellInfo::kSpreadOverflow - 1) {
        ++packed;
      } else if (packed == CellInfo::kSpreadOverflow - 1) {
        packed = CellInfo::kSpreadOverflow;
        overflow_[&*c][i] = static_cast<int64_t>(CellInfo::kSpreadOverflow);
      } else {
        ++overflow_.at(&*c)[i];
      }
    }
  }

  // Spread counts that passed the packed range during concurrent counting, per cell and face:
  // one tally per thread, added to the overflow table by MergeOverflow once the threads are done.
  using OverflowTally = std::unordered_map<const void*, std::array<int64_t, 4>>;

  // CountCrossing for several threads at once (ParallelWalks): atomic increments, and what
  // passes the packed range goes to the thread's tally (the thread whose increment reaches
  // kSpreadOverflow records that value, the later ones one each), as CountCrossing puts it in
  // the table. The same counts as CountCrossing once the tallies are merged.
  void CountCrossingConcurrently(const Cell_handle& c, unsigned spread_mask,
                                 OverflowTally* tally) const {
    CellInfo& info = c->info();
    __atomic_fetch_add(&info.crossings, 1, __ATOMIC_RELAXED);
    spread_mask = SpreadMask(spread_mask);
    for (int i = 0; i < 4; ++i) {
      if (((spread_mask >> i) & 1) == 0) continue;
      uint16_t* packed = &info.spread[i];
      uint16_t seen = __atomic_load_n(packed, __ATOMIC_RELAXED);
      for (;;) {
        if (seen == CellInfo::kSpreadOverflow) {
          ++(*tally)[&*c][i];
          break;
        }
        const uint16_t next = seen + 1;
        if (__atomic_compare_exchange_n(packed, &seen, next, /*weak=*/true, __ATOMIC_RELAXED,
                                        __ATOMIC_RELAXED)) {
          if (next == CellInfo::kSpreadOverflow) {
            (*tally)[&*c][i] += static_cast<int64_t>(CellInfo::kSpreadOverflow);
          }
          break;
        }
      }
    }
  }
  void MergeOverflow(const OverflowTally& tally) {
    for (const auto& [cell, counts] : tally) {
      std::array<int64_t, 4>& total = overflow_[cell];
      for (int i = 0; i < 4; ++i) total[i] += counts[i];
    }
  }

  // The rays that enter c first past their point (counted only with behind_ratio > 0). In a
  // table, not in CellInfo: 4 bytes there cost every run 8 bytes a cell, option on or off.
  int32_t Behind(const Cell_handle& c) const {
    const auto it = behind_.find(&*c);
    return it == behind_.end() ? 0 : it->second;
  }
  void CountBehind(const Cell_handle& c) { ++behind_[&*c]; }

  // The free-space cut's verdict on c (--manifold.visibility cut): free or not, whatever its
  // weight. Cells born since the last cut are decided by their weight until the next.
  void SetCutVerdict(const Cell_handle& c, bool free) { cut_[&*c] = free; }

  // Drops what the tables hold for c, a cell an insertion is about to destroy (its memory may
  // come back as a new cell).
  void ForgetCounts(const Cell_handle& c) {
    if (!behind_.empty()) behind_.erase(&*c);
    if (!cut_.empty()) cut_.erase(&*c);
    const uint16_t* spread = c->info().spread;
    if (std::find(spread, spread + 4, CellInfo::kSpreadOverflow) != spread + 4) {
      overflow_.erase(&*c);
    }
  }

  // Puts c into O or takes it out, keeping |O| and the per-vertex counts (cells in O, surface
  // faces, the last flip around it) up to date.
  void SetOutside(const Cell_handle& c, bool outside) {
    MS_CHECK(!dt_.is_infinite(c));
    if (c->info().outside == outside) return;
    c->info().outside = outside;
    const int delta = outside ? 1 : -1;
    outside_count_ += delta;
    ++relabels_;
    for (int i = 0; i < 4; ++i) {
      c->vertex(i)->info().outside_cells += delta;
      c->vertex(i)->info().relabelled = relabels_;
    }
    // Flipping c toggles whether each of its faces is on the surface.
    for (int i = 0; i < 4; ++i) {
      const int face_delta = InO(c->neighbor(i)) != outside ? 1 : -1;
      for (int j = 0; j < 4; ++j) {
        if (j != i) c->vertex(j)->info().surface_faces += face_delta;
      }
    }
  }

 private:
  // The faces a crossing spreads w2 across under the w2 rule (the walk's mask: camera side).
  unsigned SpreadMask(unsigned camera_side) const {
    return w2_rule_ == W2Rule::kAllFaces ? 0xFu : camera_side;
  }

  const Delaunay& dt_;
  // Weights (paper section 2.1): w1 per crossing ray, w2 per ray spreading from a neighbour.
  const double w1_, w2_, free_threshold_, behind_ratio_;
  const W2Rule w2_rule_;
  bool graded_ = false;
  // Spread counts past 16 bits, by cell (CellInfo::kSpreadOverflow).
  std::unordered_map<const void*, std::array<int64_t, 4>> overflow_;
  std::unordered_map<const void*, int32_t> behind_;
  std::unordered_map<const void*, bool> cut_;  // the free-space cut's verdicts
  int64_t outside_count_ = 0;
  uint32_t relabels_ = 0;  // flips so far (a wrap can only cost a growing some retests)
};

}  // namespace ms::manifold_detail
