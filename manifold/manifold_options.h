// Options of the manifold reconstruction (paper sections 2.1 and 2.3). The list is
// manifold/manifold_options_def.h; base/options.h derives the checks, the command line and the
// fingerprint from it.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "base/options.h"

namespace ms {

// Which face neighbours of a crossed cell a viewing ray gives w2 to (docs/design/manifold.md).
enum class W2Rule {
  // Only neighbours on the camera's side of the shared face: between the camera and the
  // crossed cell, never beyond it (behind the observed surface). The default.
  kCameraSide,
  // All four neighbours, per crossing: the paper's wording and the authors' code.
  kAllFaces,
};
const std::vector<std::pair<const char*, W2Rule>>& OptionChoices(W2Rule);

// Which cells are free space (--manifold.visibility, docs/design/manifold.md).
enum class FreeSpaceRule {
  kThreshold,  // a cell's ray weight reaches t_w (the paper)
  kCut,        // a minimum s-t cut of the cell graph (Labatut et al.)
};
const std::vector<std::pair<const char*, FreeSpaceRule>>& OptionChoices(FreeSpaceRule);

// Whether Build adds graded Steiner points (--manifold.graded-steiner).
enum class GradedSteiner { kHidden, kOn, kOff };
const std::vector<std::pair<const char*, GradedSteiner>>& OptionChoices(GradedSteiner);

// Where regrowing starts after an insertion batch (--manifold.regrow-seeds,
// docs/design/manifold.md).
enum class RegrowSeeds {
  // Every free cell sharing a face with O (the paper): any cell the batch made free, anywhere
  // along the new rays, is tried, so O is maximal again afterwards.
  kBoundary,
  // Only those with a vertex the batch touched (inserted, shrunk or gained rays): cheaper, but a
  // cell far from the batch that new rays made free is never tried.
  kChanged,
};
const std::vector<std::pair<const char*, RegrowSeeds>>& OptionChoices(RegrowSeeds);

// How swept points join the triangulation (--manifold.insertion, docs/design/accuracy.md).
enum class InsertionMode {
  // Point by point (paper section 2.3): O shrinks around each point's conflict region, a point
  // whose region cannot leave O is discarded, then O regrows from its boundary.
  kIncremental,
  // Every batch rebuilds the triangulation, the visibility and O from all points so far: no
  // point is discarded for a conflict, and O grows again from its heaviest cell.
  kRebuild,
};
const std::vector<std::pair<const char*, InsertionMode>>& OptionChoices(InsertionMode);

struct ManifoldOptions {
  static constexpr const char* kOptionGroup = "manifold";
#define MS_OPTION_LIST "manifold/manifold_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

}  // namespace ms
