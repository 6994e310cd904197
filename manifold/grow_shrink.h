// Growing and shrinking of O (paper sections 2.1 and 2.3, docs/design/manifold.md): cells flip into
// O heaviest first, or out of O around a new point's conflict region, each flip only where the
// boundary of O stays a 2-manifold (regularity.h). Internal to manifold/.
#pragma once

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "manifold/cell_labels.h"
#include "manifold/manifold_options.h"
#include "manifold/regularity.h"
#include "manifold/triangulation.h"

namespace ms::manifold_detail {

// Whether a cell around a vertex of `cells` has flipped since CellLabels::relabels() was
// `relabels`.
bool FlippedAroundSince(const std::vector<Cell_handle>& cells, uint32_t relabels);

class GrowShrink {
 public:
  // All must outlive this object.
  GrowShrink(const Delaunay& dt, const ManifoldOptions& options, CellLabels& labels,
             Regularity& regularity)
      : dt_(dt), options_(options), labels_(labels), regularity_(regularity) {}

  // A cell in the growing queue.
  struct QueueEntry {
    double weight;
    CellKey key;
    Cell_handle cell;
    // For a cell refused earlier: CellLabels::relabels() at its refusal + 1 (0: never refused).
    uint32_t refused_after = 0;
    int32_t refusal = -1;  // its entry in Refusals, if it came from there
    // Max-heap: heavier first; among equal weights the smaller key first (determinism).
    bool operator<(const QueueEntry& o) const {
      if (weight != o.weight) return weight < o.weight;
      return key > o.key;
    }
  };
  class Refusals;

  // Grows O from `seeds` through free cells, heaviest first (ties: smaller CellKey), retrying
  // refused cells until a round adds nothing.
  // The cells added are appended to `added` when it is not null. With `refusals`, its cells
  // take part too (tested only where a cell around them has flipped since), and on return it
  // holds the cells refused at the end: every free cell next to O that is not in it, if the
  // seeds and refusals held all those there were.
  // Cells lighter than `min_weight` are left out (a tile grows its cells in bands of weight,
  // tile_manifold.h).
  void Grow(const std::vector<Cell_handle>& seeds, std::vector<Cell_handle>* added = nullptr,
            Refusals* refusals = nullptr, double min_weight = 0);

  // Grows O from the heaviest free cell (with options.grow_all_components, then from the
  // heaviest free cell of every further component). Returns the cells added.
  int64_t GrowFromHeaviest();

  // Free cells not in O sharing a face with O: all of them (RegrowSeeds::kBoundary) or those
  // with a vertex marked changed in batch `changed_in` (kChanged). Where regrowing after an
  // insertion batch starts.
  std::vector<Cell_handle> BoundarySeeds(RegrowSeeds which, uint32_t changed_in) const;

  // Free cells not in O, sharing a face with O, that could flip into O keeping the surface
  // manifold: none after a complete Grow (O is maximal). Counts them, keeps the first few.
  int64_t CountJoinableCells(std::vector<Cell_handle>* first, size_t max_kept);

  // Flips every free cell of `cells` that is not in O into O at once, if every vertex of
  // theirs stays regular; otherwise changes nothing. Escapes a state greedy growing cannot
  // leave: a pocket of free space that touches O only where adding any one of its cells would
  // pinch the surface. Returns whether it flipped.
  // `matter` cells not in O flip with them though they are not free.
  bool FlipAllIfRegular(const std::vector<Cell_handle>& cells,
                        const std::vector<Cell_handle>& matter = {});
  // FlipAllIfRegular(pocket); where it does not flip, *slivers gets the matter cells that would
  // pinch a vertex of `pocket` once the pocket is in O: around each vertex that would not stay
  // regular, the cells not in O split into face-connected pieces; every piece but the largest,
  // if it has at most kMaxSliverCells cells, each crossed by no ray but weighing more than
  // nothing (rays through its neighbours spread into it).
  bool FlipAllOrFindSlivers(const std::vector<Cell_handle>& pocket,
                            std::vector<Cell_handle>* slivers);
  // FlipAllIfRegular on the cells around v, unless a free cell among them not in O weighs less
  // than `min_weight` (then nothing changes and it returns false).
  bool CompleteFreeStar(const Vertex_handle& v, double min_weight = 0);
  // Joins a pocket (from Pocket) into O: whole if FlipAllIfRegular allows it, else whole with
  // its pinching slivers (FlipAllOrFindSlivers), else the free cells around the first of its
  // surface vertices whose CompleteFreeStar(v, star_min_weight) succeeds. Vertices in `tried` are
  // skipped, and those tried are added to it. Returns the cells flipped (for a vertex: all the
  // cells around it); empty when nothing changed.
  // With `read`, a failed join appends the cells whose vertices' labels decided it (the pocket,
  // its slivers, the stars tried): it would fail again until a cell around one of those flips.
  std::vector<Cell_handle> JoinPocket(const std::vector<Cell_handle>& pocket,
                                      double star_min_weight,
                                      std::unordered_set<const void*>* tried,
                                      std::vector<Cell_handle>* read = nullptr);
  // JoinPocket's last resort for a camera's pocket (a camera stands in free space): the pocket
  // with every piece of cells not in O (matter, or another free pocket) that would pinch one of
  // its vertices, whatever its size or weight,
  // piece by piece for up to `rounds` rounds while vertices stay irregular. Returns the cells
  // flipped (the pocket's free cells first), empty when it failed. With `read`, a failure
  // appends the pieces it tried (see JoinPocket).
  // With `max_piece_cells`, only pieces of at most that many cells join, and only where the
  // pocket's free volume is at least the observed matter's (a free pocket that is not a camera's:
  // a large piece is a part of the scene, and the shell behind noisy points is matter). Pinches at
  // vertices whose star has more than `max_star` cells are not looked for (a camera's pocket
  // looks at every one: a box point's star can be the last pinch between a camera and O).
  std::vector<Cell_handle> JoinPocketWithPinches(const std::vector<Cell_handle>& pocket, int rounds,
                                                 std::vector<Cell_handle>* read = nullptr,
                                                 size_t max_piece_cells = SIZE_MAX,
                                                 int32_t max_star = kMaxSliverStar);
  // Matter cells joined by JoinPocket and JoinPocketWithPinches with their pocket so far.
  int64_t slivers_joined() const { return slivers_joined_; }
  // Rounds of JoinPocketWithPinches that took a whole piece where O touches itself, so far.
  int64_t whole_pieces_tried() const { return whole_pieces_tried_; }
  // Brings cameras left in the matter back into free space: joins the free pocket around each
  // camera in cameras_in_matter() (its start cells: start_cells(camera)) into O, whole or a
  // vertex's star at a time, with the matter that pinches it if need be, and grows on from
  // what joined (with `boundary`, from what changed). Returns the joins.
  int64_t FreeEnclosedCameras(const std::function<std::vector<int32_t>()>& cameras_in_matter,
                              const std::function<std::vector<Cell_handle>(int32_t)>& start_cells,
                              const std::function<uint32_t()>& next_stamp, Refusals* boundary);
  // Joins the pockets of free space next to O (from the cells BoundarySeeds(which, changed_in)
  // gives) that growing could not enter, and grows on from them; returns the joins. With
  // `pinch_rounds` > 0 a pocket may take the small matter pieces that pinch it. With `boundary`
  // (the refusals of the growing before) the last growing starts from what changed.
  // next_stamp: a fresh visit stamp (RayWalker::NextStamp).
  int64_t JoinFreePockets(RegrowSeeds which, uint32_t changed_in, int pinch_rounds,
                          Refusals* boundary, const std::function<uint32_t()>& next_stamp);
  // Free, not in O, and sharing a face with O: a cell growing can start from.
  bool NextToO(const Cell_handle& c) const;
  // The face neighbours of `cells` that are NextToO.
  std::vector<Cell_handle> NextToOBeside(const std::vector<Cell_handle>& cells) const;

  // The free cells not in O reachable from `start` through shared faces (at most max_cells),
  // in the order found; empty if start is not one. `stamp` (RayWalker::NextStamp) marks the
  // cells found.
  std::vector<Cell_handle> Pocket(const Cell_handle& start, size_t max_cells, uint32_t stamp);

  // Shrinks O around a new point's conflict region D (`conflicts`): removes cells of E (D,
  // then its neighbourhood, options.shrink_neighbourhood) from O where the surface stays
  // manifold, until D has left O or nothing more can be removed. Marks the vertices of removed
  // cells changed in `batch`; `stamp` (RayWalker::NextStamp) marks E while it is collected.
  // Returns whether D left O; *shrunk is increased by the cells removed.
  bool ShrinkAround(const std::vector<Cell_handle>& conflicts, uint32_t stamp, uint32_t batch,
                    int64_t* shrunk);

 private:
  // Cells flipped into O on trial, and the last-flip marks (VertexInfo::relabelled) their
  // vertices had before.
  struct TrialFlips {
    std::vector<Cell_handle> cells;
    std::vector<std::pair<Vertex_handle, uint32_t>> marks;
    // Each vertex of `cells` with the flipped cells around it, sorted by vertex. A vertex of
    // one flipped cell only has its verdict (`single_regular`, aligned) from the local test
    // before the flips (Regularity::VertexRegularAfterFlip), not from a scan of its star after.
    std::vector<std::pair<Vertex_handle, Cell_handle>> touched;
    std::vector<char> single_regular;
  };
  // Puts into O, in this order, the free cells of `cells` and the cells of `matter` (matter, or
  // free cells of another pocket that pinches this one) that are not in O yet, and returns them
  // for UndoFlips.
  TrialFlips FlipIntoO(const std::vector<Cell_handle>& cells,
                       const std::vector<Cell_handle>& matter = {});
  // Pinches at vertices of larger stars (the box's Steiner points) are left alone: their pieces
  // cost the square of the star to find.
  static constexpr int32_t kMaxSliverStar = 256;
  // Whether every vertex of trial.cells (flipped into O on trial) is regular. Stops at the
  // first that is not, unless `irregular` is given: then it gets every irregular vertex whose
  // star has at most `max_star` cells.
  bool AllRegularAfterTrial(const TrialFlips& trial, std::unordered_set<const void*>* irregular,
                            int32_t max_star = kMaxSliverStar);
  // Around each vertex of `irregular` (vertices of `joined`, cells in O on trial), the cells not
  // in O split into face-connected pieces: the finite cells of every piece but the largest that
  // accept(cell, piece size) takes. A pinch that O closes through such a piece goes away when
  // the piece joins O too. With whole_single_piece, a vertex whose cells not in O are one piece
  // (O touches itself there) gives that whole piece.
  template <class Accept>
  std::vector<Cell_handle> PinchingPieces(const std::vector<Cell_handle>& joined,
                                          const std::unordered_set<const void*>& irregular,
                                          bool whole_single_piece, Accept&& accept);
  // Takes the cells FlipIntoO put into O out again, last first, and gives their vertices back
  // their last-flip marks: a trial that is undone is no change around them, so growing and the
  // pocket joins do not test again what it touched (most of their tests on a street).
  void UndoFlips(const TrialFlips& trial);
  // Whether the free cells of `cells` hold at least the volume of its matter cells spanned by
  // input points alone (the shell between observed points; a cell with a Steiner vertex is matter
  // by default, not by observation): a pocket that would take more of that matter into O than
  // the free space it brings stays out.
  bool FreeOutweighsObservedMatter(const std::vector<Cell_handle>& cells) const;

  const Delaunay& dt_;
  const ManifoldOptions& options_;
  CellLabels& labels_;
  Regularity& regularity_;
  int64_t slivers_joined_ = 0;
  int64_t whole_pieces_tried_ = 0;
  // Reused by ShrinkAround.
  std::vector<std::pair<CellKey, Cell_handle>> shrink_set_;
  std::vector<Cell_handle> around_;
};

// Cells a Grow refused, each with CellLabels::relabels() at its refusal + 1. Whether a cell may
// join depends only on the labels of the cells around its vertices
// (Regularity::FlipKeepsManifold), so a refused cell waits aside until a cell around one of its
// vertices flips, and only then goes back into the queue, where it would have stood among the
// others: the same cells join in the same order as when every refusal is queued again, which
// on a many-camera street costs a pass over every refusal for each camera star completed.
// Kept aside across Grows (regrowing) they need an index by vertex; within one Grow (the build)
// they are simply queued again each round, which keeps the build's memory.
// Valid while no cell is made or destroyed and no weight changes (within one regrowing).
class GrowShrink::Refusals {
 public:
  enum class Kind { kRequeued, kIndexed };
  explicit Refusals(Kind kind = Kind::kIndexed) : kind_(kind) {}

  // Refused cells not in O since (kIndexed; kRequeued: those the last Grow refused).
  size_t size() const { return alive_; }
  // Turns kRequeued refusals, as a Grow left them, into kIndexed ones: indexing costs more than
  // it saves within the one large Grow that starts a regrowing, less in the Grows after it.
  void Index();
  // `cells` may have flipped since the last Grow with these refusals (a superset is fine): the
  // refused cells around their vertices take part in the next one.
  void Flipped(const std::vector<Cell_handle>& cells);

 private:
  friend class GrowShrink;
  struct Entry {
    QueueEntry queued;
    bool alive = true;
    bool woken = false;  // in the queue, or waiting for the next round
  };
  struct Link {
    int32_t entry;
    int32_t next;  // -1: the last
  };
  bool indexed() const { return kind_ == Kind::kIndexed; }
  // Keeps a refused cell aside, or renews the refusal of one kept already.
  void Add(const QueueEntry& refused);
  // The cell joined O.
  void Remove(const Cell_handle& c);
  // Calls wake(index) on each kept cell, not woken yet, with a vertex of c (kIndexed).
  template <class Wake>
  void ForEachAround(const Cell_handle& c, Wake&& wake);
  // kRequeued: every refusal, for the next round (they are kept again if refused again).
  std::vector<Entry> TakeAll();

  Kind kind_;
  std::vector<Entry> entries_;
  size_t alive_ = 0;
  std::unordered_map<const void*, int32_t> entry_of_cell_;    // kIndexed
  std::unordered_map<const void*, int32_t> first_at_vertex_;  // kIndexed: into links_
  std::vector<Link> links_;
  std::vector<int32_t> pending_;  // woken by Flipped, for the next Grow
};

}  // namespace ms::manifold_detail
