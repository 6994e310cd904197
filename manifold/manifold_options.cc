#include "manifold/manifold_options.h"

#include <cmath>
#include <string>

#include "base/error.h"

namespace ms {

void ManifoldOptions::Check() const {
  const auto require = [](bool ok, const char* field, const char* rule) {
    if (!ok) throw InputError(std::string("manifold option ") + field + ": " + rule);
  };
  require(std::isfinite(w1) && w1 > 0, "w1", "must be positive");
  require(std::isfinite(w2) && w2 >= 0, "w2", "must be >= 0");
  require(std::isfinite(free_threshold) && free_threshold > 0, "free-threshold", "must be positive");
  require(std::isfinite(steiner_margin) && steiner_margin > 0, "steiner-margin", "must be positive");
  require(steiner_grid >= 2 && steiner_grid <= 64, "steiner-grid", "must be in [2, 64]");
  require(steiner_graded == GradedSteiner::kAuto || steiner_graded == GradedSteiner::kOn ||
              steiner_graded == GradedSteiner::kOff,
          "graded-steiner", "must be auto, on or off");
  require(graded_steiner_min_points >= 0, "graded-steiner-min-points", "must be >= 0");
  require(std::isfinite(steiner_clearance) && steiner_clearance >= 1, "steiner-clearance",
          "must be >= 1");
  require(std::isfinite(steiner_min_spacing) && steiner_min_spacing > 0, "steiner-min-spacing",
          "must be positive");
  require(w2_rule == W2Rule::kCameraSide || w2_rule == W2Rule::kAllFaces, "w2-rule",
          "must be camera-side or all-faces");
  require(shrink_neighbourhood == 0 || shrink_neighbourhood == 1, "shrink-neighbourhood",
          "must be 0 (face neighbours) or 1 (vertex neighbours)");
}

}  // namespace ms
