// BatchRays: the insertion's per-ray bookkeeping for the recount of the cells it creates
// (docs/design/manifold.md, "Incremental insertion"). Internal to manifold/; no CGAL.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ms::manifold_detail {

// What an insertion batch knows of each ray in the index (by its id), stored only for the
// rays it touched: most rays are never marked in a batch, and three values for every ray
// were 120 bytes a point at 10 rays a point (docs/design/scalability.md, "Memory per point").
class BatchRays {
 public:
  struct State {
    // The smallest parameter (0 at the camera, 1 at the point) where the ray may enter a
    // cell born since its last walk; > 1: none (not pending).
    float reach = 2.0f;
    uint32_t counted = 0;  // it has been counted on every cell born in parts <= counted
    uint32_t marked = 0;   // the last part that marked it
  };
  // `rays` rays, each counted on every cell born in parts <= `counted`, none pending.
  void Reset(size_t rays, uint32_t counted) {
    slot_.assign(rays, -1);
    std::vector<State>().swap(states_);
    counted_ = counted;
  }
  // The rays added to the index since, traced in `part` (so counted on every cell there is).
  void AddTraced(size_t rays, uint32_t part) {
    while (slot_.size() < rays) {
      slot_.push_back(static_cast<int32_t>(states_.size()));
      states_.push_back({2.0f, part, 0});
    }
  }
  State Get(int32_t id) const {
    const int32_t slot = slot_[id];
    return slot < 0 ? State{2.0f, counted_, 0} : states_[slot];
  }
  State& Touch(int32_t id) {
    int32_t& slot = slot_[id];
    if (slot < 0) {
      slot = static_cast<int32_t>(states_.size());
      states_.push_back({2.0f, counted_, 0});
    }
    return states_[slot];
  }

 private:
  std::vector<int32_t> slot_;  // -1: untouched (the defaults)
  std::vector<State> states_;
  uint32_t counted_ = 0;
};

}  // namespace ms::manifold_detail
