#include "manifold/manifold_options.h"

namespace ms {

const std::vector<std::pair<const char*, W2Rule>>& OptionChoices(W2Rule) {
  static const std::vector<std::pair<const char*, W2Rule>> choices = {
      {"camera-side", W2Rule::kCameraSide}, {"all-faces", W2Rule::kAllFaces}};
  return choices;
}

const std::vector<std::pair<const char*, FreeSpaceRule>>& OptionChoices(FreeSpaceRule) {
  static const std::vector<std::pair<const char*, FreeSpaceRule>> choices = {
      {"threshold", FreeSpaceRule::kThreshold}, {"cut", FreeSpaceRule::kCut}};
  return choices;
}

const std::vector<std::pair<const char*, GradedSteiner>>& OptionChoices(GradedSteiner) {
  static const std::vector<std::pair<const char*, GradedSteiner>> choices = {
      {"hidden", GradedSteiner::kHidden}, {"on", GradedSteiner::kOn}, {"off", GradedSteiner::kOff}};
  return choices;
}

const std::vector<std::pair<const char*, RegrowSeeds>>& OptionChoices(RegrowSeeds) {
  static const std::vector<std::pair<const char*, RegrowSeeds>> choices = {
      {"boundary", RegrowSeeds::kBoundary}, {"changed", RegrowSeeds::kChanged}};
  return choices;
}

const std::vector<std::pair<const char*, InsertionMode>>& OptionChoices(InsertionMode) {
  static const std::vector<std::pair<const char*, InsertionMode>> choices = {
      {"incremental", InsertionMode::kIncremental}, {"rebuild", InsertionMode::kRebuild}};
  return choices;
}

}  // namespace ms
