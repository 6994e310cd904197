#include "manifold/grow_shrink.h"

#include <algorithm>
#include <iterator>
#include <map>
#include <queue>

namespace ms::manifold_detail {

using QueueEntry = GrowShrink::QueueEntry;

namespace {

// Splits `cells` into pieces connected through shared faces: (*piece)[k] is the piece of
// cells[k], (*sizes)[p] the number of cells in piece p. Quadratic: for the few cells of a star.
void FaceConnectedPieces(const std::vector<Cell_handle>& cells, std::vector<int>* piece,
                         std::vector<size_t>* sizes) {
  piece->assign(cells.size(), -1);
  sizes->clear();
  std::vector<size_t> stack;
  for (size_t a = 0; a < cells.size(); ++a) {
    if ((*piece)[a] >= 0) continue;
    const int id = static_cast<int>(sizes->size());
    sizes->push_back(0);
    stack.assign(1, a);
    (*piece)[a] = id;
    while (!stack.empty()) {
      const size_t k = stack.back();
      stack.pop_back();
      ++(*sizes)[id];
      for (size_t b = 0; b < cells.size(); ++b) {
        if ((*piece)[b] < 0 && cells[k]->has_neighbor(cells[b])) {
          (*piece)[b] = id;
          stack.push_back(b);
        }
      }
    }
  }
}

}  // namespace

void GrowShrink::Grow(const std::vector<Cell_handle>& seeds, std::vector<Cell_handle>* added_cells,
                      Refusals* refusals, double min_weight) {
  Refusals within(Refusals::Kind::kRequeued);
  Refusals& kept = refusals != nullptr ? *refusals : within;
  std::priority_queue<QueueEntry> queue;
  const auto push = [&](const QueueEntry& entry) {
    entry.cell->info().queued = true;
    queue.push(entry);
  };
  const auto push_new = [&](const Cell_handle& c) {
    if (c->info().queued || !labels_.FreeOutsideO(c)) return;
    const double weight = labels_.Weight(c);
    if (weight >= min_weight) push({weight, KeyOf(c), c});
  };
  // A refused cell again, its weight and key as they were: it is still free (no weight changes
  // while refusals are kept), so only whether it joined O since is asked.
  const auto push_again = [&](const QueueEntry& entry) {
    const Cell_handle& c = entry.cell;
    if (c->info().queued || c->info().outside) return false;
    push(entry);
    return true;
  };
  // Whether a cell joins depends only on the labels of the cells around its vertices
  // (Regularity::FlipKeepsManifold): one refused when no cell around them has flipped since is
  // refused again without the test. The same cells join in the same order as when every retry
  // is tested; at 10^6 cells on the boundary of O, most of regrowing was such retests.
  const auto unchanged_since = [](const Cell_handle& c, uint32_t refused_after) {
    if (refused_after == 0) return false;
    for (int i = 0; i < 4; ++i) {
      if (c->vertex(i)->info().relabelled >= refused_after) return false;
    }
    return true;
  };
  // The lowest entry (in queue order) taken this round. A kept refusal above it would already
  // have been taken, and refused again unchanged, had all refusals been queued at the start of
  // the round: woken by a flip now it waits for the next round, below it it joins the queue.
  bool taken_any = false;
  QueueEntry lowest_taken{};
  std::vector<int32_t> next_round;
  const auto wake = [&](int32_t index) {
    Refusals::Entry& r = kept.entries_[index];
    if (r.queued.cell->info().queued) return;  // queued anew: that test will be the current one
    r.woken = true;
    if (!taken_any || r.queued < lowest_taken) {
      push(r.queued);
    } else {
      next_round.push_back(index);
    }
  };
  if (kept.indexed()) {
    for (const int32_t index : kept.pending_) {
      Refusals::Entry& r = kept.entries_[index];
      r.woken = false;
      if (r.alive) wake(index);
    }
    kept.pending_.clear();
  } else {
    for (const Refusals::Entry& r : kept.TakeAll()) push_again(r.queued);
  }
  for (const Cell_handle& c : seeds) push_new(c);
  for (;;) {
    int64_t added = 0;
    taken_any = false;
    while (!queue.empty()) {
      const QueueEntry entry = queue.top();
      const Cell_handle c = entry.cell;
      queue.pop();
      c->info().queued = false;
      if (!taken_any || entry < lowest_taken) lowest_taken = entry;
      taken_any = true;
      if (entry.refusal >= 0) kept.entries_[entry.refusal].woken = false;
      if (c->info().outside) continue;
      const bool refused_again = unchanged_since(c, entry.refused_after);
      if (!refused_again && regularity_.FlipKeepsManifold(c)) {
        labels_.SetOutside(c, true);
        ++added;
        if (added_cells != nullptr) added_cells->push_back(c);
        kept.Remove(c);
        // Before the neighbours: a kept one that is queued again is not queued anew.
        kept.ForEachAround(c, wake);
        for (int i = 0; i < 4; ++i) push_new(c->neighbor(i));
      } else if (!refused_again) {
        QueueEntry refused = entry;
        refused.refused_after = labels_.relabels() + 1;
        kept.Add(refused);
      } else if (!kept.indexed()) {
        kept.Add(entry);
      }
    }
    // A cell refused earlier may be accepted now that O has changed around it: retry until
    // a round adds nothing.
    if (added == 0) break;
    bool queued_any = false;
    if (kept.indexed()) {
      for (const int32_t index : next_round) {
        Refusals::Entry& r = kept.entries_[index];
        r.woken = false;
        if (r.alive && push_again(r.queued)) {
          r.woken = true;
          queued_any = true;
        }
      }
      next_round.clear();
    } else {
      for (const Refusals::Entry& r : kept.TakeAll()) queued_any |= push_again(r.queued);
    }
    if (!queued_any) break;
  }
  for (const int32_t index : next_round) kept.entries_[index].woken = false;
}

bool FlippedAroundSince(const std::vector<Cell_handle>& cells, uint32_t relabels) {
  for (const auto& c : cells) {
    for (int i = 0; i < 4; ++i) {
      if (c->vertex(i)->info().relabelled > relabels) return true;
    }
  }
  return false;
}

void GrowShrink::Refusals::Flipped(const std::vector<Cell_handle>& cells) {
  for (const Cell_handle& c : cells) {
    if (c->info().outside) Remove(c);
    ForEachAround(c, [&](int32_t index) {
      entries_[index].woken = true;
      pending_.push_back(index);
    });
  }
}

void GrowShrink::Refusals::Index() {
  if (indexed()) return;
  kind_ = Kind::kIndexed;
  std::vector<Entry> requeued = TakeAll();
  entry_of_cell_.reserve(requeued.size());
  first_at_vertex_.reserve(2 * requeued.size());
  links_.reserve(4 * requeued.size());
  for (const Entry& r : requeued) {
    if (!r.queued.cell->info().outside) Add(r.queued);
  }
}

void GrowShrink::Refusals::Add(const QueueEntry& refused) {
  if (indexed()) {
    const auto [at, added] = entry_of_cell_.emplace(&*refused.cell, 0);
    if (!added) {
      // The later refusal: a test then that no flip around it has outdated since.
      uint32_t& after = entries_[at->second].queued.refused_after;
      after = std::max(after, refused.refused_after);
      return;
    }
    at->second = static_cast<int32_t>(entries_.size());
    for (int i = 0; i < 4; ++i) {
      const auto [first, none_yet] = first_at_vertex_.emplace(&*refused.cell->vertex(i), -1);
      links_.push_back({at->second, first->second});
      first->second = static_cast<int32_t>(links_.size() - 1);
    }
  }
  entries_.push_back({refused});
  entries_.back().queued.refusal = indexed() ? static_cast<int32_t>(entries_.size() - 1) : -1;
  ++alive_;
}

void GrowShrink::Refusals::Remove(const Cell_handle& c) {
  if (!indexed()) return;
  const auto at = entry_of_cell_.find(&*c);
  if (at == entry_of_cell_.end()) return;
  entries_[at->second].alive = false;
  entry_of_cell_.erase(at);
  --alive_;
}

template <class Wake>
void GrowShrink::Refusals::ForEachAround(const Cell_handle& c, Wake&& wake) {
  if (!indexed()) return;
  for (int i = 0; i < 4; ++i) {
    const auto first = first_at_vertex_.find(&*c->vertex(i));
    if (first == first_at_vertex_.end()) continue;
    for (int32_t link = first->second; link >= 0; link = links_[link].next) {
      const Refusals::Entry& r = entries_[links_[link].entry];
      if (r.alive && !r.woken) wake(links_[link].entry);
    }
  }
}

std::vector<GrowShrink::Refusals::Entry> GrowShrink::Refusals::TakeAll() {
  std::vector<Entry> all;
  all.swap(entries_);
  alive_ = 0;
  return all;
}

int64_t GrowShrink::GrowFromHeaviest() {
  const int64_t before = labels_.outside_count();
  for (;;) {
    Cell_handle best;
    QueueEntry best_entry{-1, {}, Cell_handle()};
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (!labels_.FreeOutsideO(c)) continue;
      if (labels_.outside_count() > 0) {
        // Later seeds must start a separate component: no vertex touching O.
        bool touches = false;
        for (int i = 0; i < 4; ++i) touches |= c->vertex(i)->info().outside_cells > 0;
        if (touches) continue;
      }
      const QueueEntry entry{labels_.Weight(c), KeyOf(c), c};
      if (best == Cell_handle() || best_entry < entry) {
        best = c;
        best_entry = entry;
      }
    }
    if (best == Cell_handle()) break;
    Grow({best});
    if (!options_.grow_all_components) break;
  }
  return labels_.outside_count() - before;
}

std::vector<Cell_handle> GrowShrink::BoundarySeeds(RegrowSeeds which, uint32_t changed_in) const {
  std::vector<Cell_handle> seeds;
  for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
    if (!labels_.FreeOutsideO(c)) continue;
    if (which == RegrowSeeds::kChanged) {
      bool changed = false;
      for (int i = 0; i < 4; ++i) changed |= c->vertex(i)->info().changed == changed_in;
      if (!changed) continue;
    }
    if (NextToO(c)) seeds.push_back(c);
  }
  return seeds;
}

bool GrowShrink::NextToO(const Cell_handle& c) const {
  if (!labels_.FreeOutsideO(c)) return false;
  for (int i = 0; i < 4; ++i) {
    if (labels_.InO(c->neighbor(i))) return true;
  }
  return false;
}

std::vector<Cell_handle> GrowShrink::NextToOBeside(const std::vector<Cell_handle>& cells) const {
  std::vector<Cell_handle> beside;
  for (const Cell_handle& c : cells) {
    for (int i = 0; i < 4; ++i) {
      if (NextToO(c->neighbor(i))) beside.push_back(c->neighbor(i));
    }
  }
  return beside;
}

int64_t GrowShrink::CountJoinableCells(std::vector<Cell_handle>* first, size_t max_kept) {
  int64_t joinable = 0;
  for (const Cell_handle& c : BoundarySeeds(RegrowSeeds::kBoundary, 0)) {
    if (!regularity_.FlipKeepsManifold(c)) continue;
    ++joinable;
    if (first != nullptr && first->size() < max_kept) first->push_back(c);
  }
  return joinable;
}

bool GrowShrink::FlipAllIfRegular(const std::vector<Cell_handle>& cells,
                                  const std::vector<Cell_handle>& matter) {
  const TrialFlips trial = FlipIntoO(cells, matter);
  if (trial.cells.empty()) return false;
  const bool regular = AllRegularAfterTrial(trial, nullptr);
  if (!regular) UndoFlips(trial);
  return regular;
}

GrowShrink::TrialFlips GrowShrink::FlipIntoO(const std::vector<Cell_handle>& cells,
                                             const std::vector<Cell_handle>& matter) {
  TrialFlips trial;
  // Another tile's cell never flips here (tile_manifold.h): a trial that needs one is none.
  for (const Cell_handle& c : matter) {
    if (c->info().frozen && !c->info().outside) return trial;
  }
  std::vector<Cell_handle>& flipped = trial.cells;
  for (const Cell_handle& c : cells) {
    if (labels_.FreeOutsideO(c)) flipped.push_back(c);
  }
  for (const Cell_handle& c : matter) {
    if (!dt_.is_infinite(c) && !c->info().outside) flipped.push_back(c);
  }
  // Most vertices of a small pocket belong to one of its cells; each such vertex is decided
  // now, while the labels around it are those the local test reasons from.
  std::vector<std::pair<Vertex_handle, Cell_handle>>& touched = trial.touched;
  for (const Cell_handle& c : flipped) {
    for (int i = 0; i < 4; ++i) touched.emplace_back(c->vertex(i), c);
  }
  std::sort(touched.begin(), touched.end());
  trial.single_regular.assign(touched.size(), 0);
  for (size_t k = 0; k < touched.size(); ++k) {
    const bool single = (k == 0 || touched[k - 1].first != touched[k].first) &&
                        (k + 1 == touched.size() || touched[k + 1].first != touched[k].first);
    if (single) {
      trial.single_regular[k] =
          regularity_.VertexRegularAfterFlip(touched[k].first, touched[k].second);
    }
  }
  for (const Cell_handle& c : flipped) {
    for (int i = 0; i < 4; ++i)
      trial.marks.emplace_back(c->vertex(i), c->vertex(i)->info().relabelled);
    labels_.SetOutside(c, true);
  }
  return trial;
}

void GrowShrink::UndoFlips(const TrialFlips& trial) {
  const std::vector<Cell_handle>& flipped = trial.cells;
  for (auto c = flipped.rbegin(); c != flipped.rend(); ++c) labels_.SetOutside(*c, false);
  // Last saved first: a vertex of several cells ends with the mark it had before the trial.
  for (auto m = trial.marks.rbegin(); m != trial.marks.rend(); ++m) {
    m->first->info().relabelled = m->second;
  }
}

bool GrowShrink::CompleteFreeStar(const Vertex_handle& v, double min_weight) {
  around_.clear();
  dt_.incident_cells(v, std::back_inserter(around_));
  for (const Cell_handle& c : around_) {
    if (labels_.FreeOutsideO(c) && labels_.Weight(c) < min_weight) {
      return false;
    }
  }
  return FlipAllIfRegular(std::vector<Cell_handle>(around_.begin(), around_.end()));
}

bool GrowShrink::AllRegularAfterTrial(const TrialFlips& trial,
                                      std::unordered_set<const void*>* irregular,
                                      int32_t max_star) {
  // A vertex's link depends only on the labels of its own cells: the vertices of the flipped
  // cells are tested, each with the flipped cells around it.
  const std::vector<std::pair<Vertex_handle, Cell_handle>>& touched = trial.touched;
  // Scanning a star costs its size; a box point's star can hold 10^4 cells and be tested
  // after every flip near it (pocket joins at 10^6 points spent minutes there).
  constexpr int32_t kLargeStar = 64;
  bool all_regular = true;
  std::vector<Cell_handle> near;
  for (size_t k = 0; k < touched.size();) {
    const Vertex_handle w = touched[k].first;
    const size_t first = k;
    near.clear();
    for (; k < touched.size() && touched[k].first == w; ++k) near.push_back(touched[k].second);
    // Once one is irregular, only the stars `irregular` collects are worth a test.
    if (!all_regular && w->info().cells > max_star) continue;
    bool regular;
    if (near.size() == 1) {
      regular = trial.single_regular[first];
    } else if (w->info().cells > kLargeStar) {
      regular = regularity_.VertexRegularByLinkWalk(w, near);
    } else {
      regular = regularity_.VertexRegular(w, Cell_handle());
    }
    if (regular) continue;
    all_regular = false;
    if (irregular == nullptr) break;
    if (w->info().cells <= max_star) irregular->insert(&*w);
  }
  return all_regular;
}

bool GrowShrink::FlipAllOrFindSlivers(const std::vector<Cell_handle>& pocket,
                                      std::vector<Cell_handle>* slivers) {
  constexpr size_t kMaxSliverCells = 3;
  slivers->clear();
  // One trial serves both: the pocket goes into O, stays if every vertex is regular, else the
  // pinches are looked for there and it goes out again.
  const TrialFlips trial = FlipIntoO(pocket);
  if (trial.cells.empty()) return false;
  std::unordered_set<const void*> irregular;
  if (AllRegularAfterTrial(trial, &irregular)) return true;
  *slivers = PinchingPieces(trial.cells, irregular, /*whole_single_piece=*/false,
                            [&](const Cell_handle& c, size_t piece_size) {
                              return piece_size <= kMaxSliverCells && c->info().crossings == 0 &&
                                     labels_.Weight(c) > 0;
                            });
  UndoFlips(trial);
  return false;
}

template <class Accept>
std::vector<Cell_handle> GrowShrink::PinchingPieces(
    const std::vector<Cell_handle>& joined, const std::unordered_set<const void*>& irregular,
    bool whole_single_piece, Accept&& accept) {
  std::vector<Cell_handle> pieces;
  std::unordered_set<const void*> seen_vertices, seen_cells;
  std::vector<Cell_handle> star, rest;
  std::vector<int> piece;
  std::vector<size_t> sizes;
  for (const Cell_handle& joined_cell : joined) {
    for (int i = 0; i < 4; ++i) {
      const Vertex_handle v = joined_cell->vertex(i);
      if (!seen_vertices.insert(&*v).second || irregular.count(&*v) == 0) continue;
      star.clear();
      dt_.incident_cells(v, std::back_inserter(star));
      rest.clear();
      for (const Cell_handle& c : star) {
        if (!labels_.InO(c)) rest.push_back(c);
      }
      FaceConnectedPieces(rest, &piece, &sizes);
      if (sizes.size() < 2 && !whole_single_piece) continue;
      // One piece: O pinches itself at v, and only the whole piece joining O mends it.
      const auto largest =
          sizes.size() < 2 ? -1 : std::max_element(sizes.begin(), sizes.end()) - sizes.begin();
      for (size_t a = 0; a < rest.size(); ++a) {
        const Cell_handle& c = rest[a];
        if (piece[a] == largest || dt_.is_infinite(c) || !accept(c, sizes[piece[a]])) continue;
        if (seen_cells.insert(&*c).second) pieces.push_back(c);
      }
    }
  }
  return pieces;
}

bool GrowShrink::FreeOutweighsObservedMatter(const std::vector<Cell_handle>& cells) const {
  double free_volume = 0, observed_matter_volume = 0;
  for (const Cell_handle& c : cells) {
    if (dt_.is_infinite(c)) continue;
    const double volume =
        std::abs(CGAL::to_double(CGAL::volume(c->vertex(0)->point(), c->vertex(1)->point(),
                                              c->vertex(2)->point(), c->vertex(3)->point())));
    if (labels_.IsFree(c)) {
      free_volume += volume;
    } else if (c->vertex(0)->info().id >= 0 && c->vertex(1)->info().id >= 0 &&
               c->vertex(2)->info().id >= 0 && c->vertex(3)->info().id >= 0) {
      observed_matter_volume += volume;
    }
  }
  return observed_matter_volume <= free_volume;
}

std::vector<Cell_handle> GrowShrink::JoinPocketWithPinches(const std::vector<Cell_handle>& pocket,
                                                           int rounds,
                                                           std::vector<Cell_handle>* read,
                                                           size_t max_piece_cells,
                                                           int32_t max_star) {
  std::vector<Cell_handle> matter;
  for (int round = 0; round < rounds; ++round) {
    const TrialFlips trial = FlipIntoO(pocket, matter);
    if (trial.cells.empty()) return {};
    std::unordered_set<const void*> irregular;
    if (AllRegularAfterTrial(trial, &irregular, max_star)) {
      if (max_piece_cells != SIZE_MAX && !FreeOutweighsObservedMatter(trial.cells)) {
        UndoFlips(trial);
        return {};
      }
      slivers_joined_ += static_cast<int64_t>(trial.cells.size() - pocket.size());
      return trial.cells;
    }
    // Matter pinches first; where O touches itself, the whole piece only when nothing else is left.
    const auto small = [&](const Cell_handle&, size_t size) { return size <= max_piece_cells; };
    std::vector<Cell_handle> pieces = PinchingPieces(trial.cells, irregular, false, small);
    if (pieces.empty()) {
      pieces = PinchingPieces(trial.cells, irregular, true, small);
      whole_pieces_tried_ += !pieces.empty();
    }
    UndoFlips(trial);
    if (read != nullptr) read->insert(read->end(), pieces.begin(), pieces.end());
    if (pieces.empty()) return {};
    matter.insert(matter.end(), pieces.begin(), pieces.end());
  }
  return {};
}

std::vector<Cell_handle> GrowShrink::JoinPocket(const std::vector<Cell_handle>& pocket,
                                                double star_min_weight,
                                                std::unordered_set<const void*>* tried,
                                                std::vector<Cell_handle>* read) {
  std::vector<Cell_handle> slivers;
  if (FlipAllOrFindSlivers(pocket, &slivers)) return pocket;
  if (!slivers.empty() && FlipAllIfRegular(pocket, slivers)) {
    slivers_joined_ += static_cast<int64_t>(slivers.size());
    std::vector<Cell_handle> flipped = pocket;
    flipped.insert(flipped.end(), slivers.begin(), slivers.end());
    return flipped;
  }
  if (read != nullptr) {
    read->insert(read->end(), pocket.begin(), pocket.end());
    read->insert(read->end(), slivers.begin(), slivers.end());
  }
  for (const Cell_handle& cell : pocket) {
    for (int i = 0; i < 4; ++i) {
      const Vertex_handle v = cell->vertex(i);
      if (v->info().outside_cells == 0 || !tried->insert(&*v).second) continue;
      if (CompleteFreeStar(v, star_min_weight)) {
        std::vector<Cell_handle> star;
        dt_.incident_cells(v, std::back_inserter(star));
        return star;
      }
      if (read != nullptr) read->insert(read->end(), around_.begin(), around_.end());
    }
  }
  return {};
}

std::vector<Cell_handle> GrowShrink::Pocket(const Cell_handle& start, size_t max_cells,
                                            uint32_t stamp) {
  // Not yet found (stamp), and free space not in O.
  const auto joins = [&](const Cell_handle& c) {
    return c->info().stamp != stamp && labels_.FreeOutsideO(c);
  };
  std::vector<Cell_handle> pocket;
  if (!joins(start)) return pocket;
  start->info().stamp = stamp;
  pocket.push_back(start);
  for (size_t k = 0; k < pocket.size() && pocket.size() < max_cells; ++k) {
    for (int i = 0; i < 4; ++i) {
      const Cell_handle n = pocket[k]->neighbor(i);
      if (!joins(n)) continue;
      n->info().stamp = stamp;
      pocket.push_back(n);
    }
  }
  return pocket;
}

// Growing adds one cell at a time, so a pocket of free space that touches O only where each
// single cell would pinch the surface stays out of O, and with it what lies behind it: on open
// scenes such pockets stand in front of the cameras as fins of matter (docs/design/manifold.md,
// "Pockets of free space"). Each pocket next to O joins whole if every vertex stays regular,
// else the free cells around one of its surface vertices at a time (each vertex tried once a
// round, and only if those cells are well crossed); growing goes on from what joined. Later rounds
// look only at the pockets around what entered O and at refused ones around which a cell has
// flipped since (a refusal depends on the labels around the pocket's vertices), so that a round
// costs what changed, not a scan.
int64_t GrowShrink::JoinFreePockets(RegrowSeeds which, uint32_t changed_in, int pinch_rounds,
                                    Refusals* boundary,
                                    const std::function<uint32_t()>& next_stamp) {
  if (!options_.join_pockets) return 0;
  constexpr size_t kMaxPocketCells = 1 << 16;
  // A vertex's free cells join only if each weighs twice the free threshold (two crossing
  // rays): on castle-P30, whose sparse points are noisy, joining singly-crossed cells too cost
  // 1.6 points of photo-consistency; the street keeps its gain without them
  // (docs/design/manifold.md).
  const double star_min_weight = 2 * options_.free_threshold;
  // A free pocket joins with the matter that pinches it (--manifold.pocket-pinch-rounds) only
  // piece by piece of at most this many cells: larger pieces are the scene. Fewer leave fins on
  // the pyramids, more take the street's buildings into O (docs/design/accuracy.md measures both).
  constexpr size_t kMaxPinchPieceCells = 16;
  struct Refused {
    std::vector<Cell_handle> pocket;
    uint32_t relabels = 0;  // labels_.relabels() when it was refused
  };
  // The cells next to O (GrowShrink::NextToO) around the vertices of `cells`, each once: where
  // growing or a pocket may have become possible when `cells` joined O. Each vertex's star is
  // scanned once, however many of `cells` hold it (a box point's star can hold 10^4 cells):
  // a repeated star adds nothing, its cells are all stamped already.
  std::vector<Cell_handle> incident;
  std::unordered_set<const void*> scanned;
  const auto around = [&](const std::vector<Cell_handle>& cells) {
    std::vector<Vertex_handle> vertices;
    scanned.clear();
    for (const Cell_handle& c : cells) {
      for (int i = 0; i < 4; ++i) {
        if (scanned.insert(&*c->vertex(i)).second) vertices.push_back(c->vertex(i));
      }
    }
    const uint32_t found = next_stamp();
    std::vector<Cell_handle> out;
    for (const Vertex_handle& v : vertices) {
      incident.clear();
      dt_.incident_cells(v, std::back_inserter(incident));
      for (const Cell_handle& n : incident) {
        if (n->info().stamp == found) continue;
        n->info().stamp = found;
        if (NextToO(n)) out.push_back(n);
      }
    }
    return out;
  };
  int64_t joined = 0;
  std::vector<Cell_handle> seeds = BoundarySeeds(which, changed_in);
  std::vector<Refused> refused;
  std::vector<Cell_handle> all_entered;  // with `boundary`: what joined O here
  while (!seeds.empty()) {
    const uint32_t stamp = next_stamp();
    std::unordered_set<const void*> tried;
    std::vector<Cell_handle> entered;
    std::vector<Refused> refused_now;
    for (const Cell_handle& seed : seeds) {
      std::vector<Cell_handle> pocket = Pocket(seed, kMaxPocketCells, stamp);
      if (pocket.empty()) continue;  // joined, or found from an earlier seed
      std::vector<Cell_handle> flipped_cells = JoinPocket(pocket, star_min_weight, &tried);
      if (flipped_cells.empty() && pinch_rounds > 0) {
        flipped_cells = JoinPocketWithPinches(pocket, pinch_rounds, nullptr, kMaxPinchPieceCells);
      }
      if (flipped_cells.empty()) {
        refused_now.push_back({std::move(pocket), labels_.relabels()});
        continue;
      }
      ++joined;
      for (const Cell_handle& c : flipped_cells) {
        if (c->info().outside) entered.push_back(c);
      }
    }
    if (entered.empty()) break;
    // Grow from around what joined; then look at the pockets next to everything that entered
    // O, and again at the refused pockets around whose vertices a cell has flipped.
    Grow(around(entered), &entered);
    if (boundary != nullptr) all_entered.insert(all_entered.end(), entered.begin(), entered.end());
    seeds = around(entered);
    std::vector<Refused> still_refused;
    for (std::vector<Refused>* list : {&refused, &refused_now}) {
      for (Refused& r : *list) {
        // Next to what entered O, if anything.
        if (!labels_.FreeOutsideO(r.pocket.front())) continue;
        if (FlippedAroundSince(r.pocket, r.relabels)) {
          seeds.push_back(r.pocket.front());
        } else {
          still_refused.push_back(std::move(r));
        }
      }
    }
    refused = std::move(still_refused);
  }
  // Growing from the local seeds above retries only cells near what joined: one growing from
  // the whole boundary keeps O maximal for single cells.
  if (joined > 0 && boundary != nullptr) {
    // The free cells next to O now: those in `boundary` and those beside what entered.
    boundary->Flipped(all_entered);
    Grow(NextToOBeside(all_entered), nullptr, boundary);
  } else if (joined > 0) {
    Grow(BoundarySeeds(which, changed_in));
  }
  return joined;
}

// A camera stands in free space, but greedy growing can leave the free cells around one out of
// O: a pocket that touches O only where adding any one cell would pinch the surface (seen after
// an insertion re-triangulated the space in front of a camera). Completing the star of a vertex
// where the pocket touches O adds several cells at once (the whole pocket at once is tried
// first); growing then goes on from there.
int64_t GrowShrink::FreeEnclosedCameras(
    const std::function<std::vector<int32_t>()>& cameras_in_matter,
    const std::function<std::vector<Cell_handle>(int32_t)>& start_cells,
    const std::function<uint32_t()>& next_stamp, Refusals* boundary) {
  constexpr size_t kMaxPocketCells = 1 << 16;
  // Rounds of pinching matter added to a camera's pocket (camera 5 of the upward pyramid with
  // --sweep.winners-must-move took 3; docs/design/manifold.md "Known limits").
  constexpr int kMaxPinchRounds = 8;
  // A camera's pocket that could not join, with the cells its trial read: it fails again
  // until a cell around their vertices flips. Trying every camera still in the matter again
  // after each star completed would cost most of the repair on a street of thousands of cameras.
  struct Failed {
    uint32_t relabels;
    std::vector<Cell_handle> read;
  };
  std::map<std::pair<int32_t, const void*>, Failed> failed;
  for (int64_t completed = 0;; ++completed) {
    std::vector<Cell_handle> joined;
    for (const int32_t camera : cameras_in_matter()) {
      for (const Cell_handle& start : start_cells(camera)) {
        const std::pair<int32_t, const void*> key(camera, &*start);
        const auto before = failed.find(key);
        if (before != failed.end() &&
            !FlippedAroundSince(before->second.read, before->second.relabels)) {
          continue;
        }
        const std::vector<Cell_handle> pocket = Pocket(start, kMaxPocketCells, next_stamp());
        std::unordered_set<const void*> tried;
        std::vector<Cell_handle> read = {start};
        joined = JoinPocket(pocket, /*star_min_weight=*/0, &tried, &read);
        if (joined.empty())
          joined = JoinPocketWithPinches(pocket, kMaxPinchRounds, &read, SIZE_MAX, INT32_MAX);
        if (!joined.empty()) break;
        failed[key] = {labels_.relabels(), std::move(read)};
      }
      if (!joined.empty()) break;
    }
    if (joined.empty()) return completed;
    if (boundary == nullptr) {
      Grow(BoundarySeeds(RegrowSeeds::kBoundary, 0));
      continue;
    }
    // The free cells next to O now: those next to it before (in `boundary`) and the face
    // neighbours of what joined. The same growing as from a scan of every cell, without the
    // scan, and without testing again the cells around which nothing has flipped.
    boundary->Flipped(joined);
    Grow(NextToOBeside(joined), nullptr, boundary);
  }
}

bool GrowShrink::ShrinkAround(const std::vector<Cell_handle>& conflicts, uint32_t stamp,
                              uint32_t batch, int64_t* shrunk) {
  // E: the cells of D in O first, then those of its neighbourhood, each part sorted by key.
  std::vector<std::pair<CellKey, Cell_handle>>& shrink_set = shrink_set_;
  shrink_set.clear();
  const auto add_to_shrink_set = [&](const Cell_handle& c) {
    if (dt_.is_infinite(c) || c->info().stamp == stamp) return;
    c->info().stamp = stamp;
    if (c->info().outside) shrink_set.push_back({KeyOf(c), c});
  };
  const auto by_key = [](const auto& x, const auto& y) { return x.first < y.first; };
  // Adds D's face neighbours, or the stars of D's vertices: all of them (1), or only those of
  // points (2): a Steiner vertex's star reaches from the surface to the cameras, and what was
  // shrunk there did not regrow.
  enum class Around { kFaces, kAllVertices, kPointVertices };
  const auto add_neighbourhood = [&](Around around) {
    const size_t begin = shrink_set.size();
    for (const Cell_handle& c : conflicts) {
      for (int i = 0; i < 4; ++i) {
        if (around == Around::kFaces) {
          add_to_shrink_set(c->neighbor(i));
          continue;
        }
        const Vertex_handle v = c->vertex(i);
        if (around == Around::kPointVertices && (dt_.is_infinite(v) || v->info().id < 0)) continue;
        around_.clear();
        dt_.incident_cells(v, std::back_inserter(around_));
        for (const Cell_handle& a : around_) add_to_shrink_set(a);
      }
    }
    std::sort(shrink_set.begin() + begin, shrink_set.end(), by_key);
  };
  for (const Cell_handle& c : conflicts) add_to_shrink_set(c);
  const size_t num_in_d = shrink_set.size();
  if (num_in_d == 0) return true;
  std::sort(shrink_set.begin(), shrink_set.end(), by_key);
  const int neighbourhood = options_.shrink_neighbourhood;
  add_neighbourhood(neighbourhood == 1 ? Around::kAllVertices : Around::kFaces);
  size_t d_in_o = num_in_d;
  const auto remove_while_manifold = [&] {
    for (bool changed = true; changed && d_in_o > 0;) {
      changed = false;
      for (size_t k = 0; k < shrink_set.size() && d_in_o > 0; ++k) {
        const Cell_handle& c = shrink_set[k].second;
        if (c->info().outside && regularity_.FlipKeepsManifold(c)) {
          labels_.SetOutside(c, false);
          for (int i = 0; i < 4; ++i) c->vertex(i)->info().changed = batch;
          ++*shrunk;
          changed = true;
          if (k < num_in_d) --d_in_o;
        }
      }
    }
  };
  remove_while_manifold();
  // 2: only where the face neighbours were not enough, the stars of D's points too.
  if (d_in_o > 0 && neighbourhood == 2) {
    add_neighbourhood(Around::kPointVertices);
    remove_while_manifold();
  }
  return d_in_o == 0;
}

}  // namespace ms::manifold_detail
