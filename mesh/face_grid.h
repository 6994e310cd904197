// The candidate pairs of a focused check (mesh/float_robustness.h PairCandidates) from a grid of
// cells that follows the faces as they change. A box search sorts the box of every face for
// every check; a remeshing pass that changes a few thousand faces of a mesh of millions
// (refine/remesh.h) looks only at the cells around them.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "mesh/float_robustness.h"
#include "mesh/mesh.h"

namespace ms {

class FaceGrid {
 public:
  // Every face of `mesh`, each over its box grown by `tolerance` (the check's absolute
  // tolerance), in cubic cells about twice the median face's size.
  FaceGrid(const Mesh& mesh, double tolerance);

  // Face f of `mesh` changed its corners, or is new (f == the faces the grid holds).
  void Update(const Mesh& mesh, int32_t f);
  // The faces were renumbered: face f is now new_index[f], or gone where that is negative.
  void Renumber(const std::vector<int64_t>& new_index);

  // Every face pair (f < g) with a face flagged in `focus` whose grown boxes meet, those sharing a
  // vertex included, and every vertex pair (u < v) of such a pair's faces or of one flagged face:
  // a superset of what a check of `mesh` focused on `focus` with the grid's tolerance finds among
  // (FloatRobustnessOptions::candidates), sorted. The grid must hold `mesh` as it is.
  PairCandidates Candidates(const Mesh& mesh, const std::vector<uint8_t>& focus) const;

  size_t num_faces() const { return placed_.size(); }

 private:
  // Where a face is: its grown box and the cells that box covers (none for an oversized face,
  // kept in its own list).
  struct Place {
    Eigen::Vector3d lo, hi;
    std::array<int32_t, 3> from{}, to{};  // cell indices, inclusive
    bool oversized = false;
  };
  Place PlaceOf(const Mesh& mesh, int32_t f) const;
  void Add(int32_t f, const Place& place);
  void Remove(int32_t f);
  static uint64_t CellKey(int32_t x, int32_t y, int32_t z);
  template <typename Visit>
  void ForEachNear(const Place& place, Visit&& visit) const;

  double tolerance_;
  double cell_ = 1;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  std::vector<Place> placed_;  // by face
  std::unordered_map<uint64_t, std::vector<int32_t>> cells_;
  std::unordered_set<int32_t> oversized_;
};

}  // namespace ms
