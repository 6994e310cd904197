// What both kernels share (sweep/sweep_kernel.h): a tile winner's point and the prepared stats.
// The preparation itself is tested with the reference (reference_sweep_test.cc).
#include "sweep/sweep_kernel.h"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace ms {
namespace {

PreparedSweep ThreeNeighbours() {
  PreparedSweep prep;
  prep.camera.id = 7;
  for (int32_t id : {11, 12, 13}) {
    SweepCamera neighbour;
    neighbour.id = id;
    prep.neighbours.push_back(neighbour);
  }
  return prep;
}

TEST(SweepKernel, MakeSweepPointCopiesTheWinner) {
  const PreparedSweep prep = ThreeNeighbours();
  TileWinner winner;
  winner.ncc = 0.991f;
  winner.offset = -3;
  winner.neighbour = 1;
  winner.col = 4;
  winner.row = 2;
  winner.face = 42;
  winner.position = {1.5, -2, 3.25};
  const SweepPoint point = MakeSweepPoint(winner, prep);
  EXPECT_EQ(point.position, Eigen::Vector3d(1.5, -2, 3.25));
  EXPECT_EQ(point.ncc, 0.991f);
  EXPECT_EQ(point.pixel, Eigen::Vector2f(4.5f, 2.5f));  // the pixel's centre
  EXPECT_EQ(point.offset, -3);
  EXPECT_EQ(point.face, 42);
  // C, then the winning neighbour.
  EXPECT_EQ(point.cameras, (std::vector<int32_t>{7, 12}));
}

TEST(SweepKernel, MakeSweepPointListsTheOtherMatchesAfterTheWinner) {
  const PreparedSweep prep = ThreeNeighbours();
  TileWinner winner;
  winner.neighbour = 2;
  winner.col = winner.row = 0;
  winner.matched = {0, 1};
  EXPECT_EQ(MakeSweepPoint(winner, prep).cameras, (std::vector<int32_t>{7, 13, 11, 12}));
}

TEST(SweepKernel, MakeSweepPointGivesTheFullResolutionPixel) {
  PreparedSweep prep = ThreeNeighbours();
  prep.scale_x = 0.5;  // swept at half the width and a quarter of the height
  prep.scale_y = 0.25;
  TileWinner winner;
  winner.neighbour = 0;
  winner.col = 4;
  winner.row = 2;
  // Centre (4.5, 2.5) at the swept resolution: (9, 10) at full resolution (corner origin).
  EXPECT_EQ(MakeSweepPoint(winner, prep).pixel, Eigen::Vector2f(9, 10));
}

TEST(SweepKernel, WinnersMergeInSweepOrder) {
  TileWinner empty, a;
  a.ncc = 0.99f;
  a.offset = 2;
  a.neighbour = 1;
  a.row = 5;
  a.col = 7;
  EXPECT_TRUE(BeatsInSweepOrder(a, empty));
  EXPECT_FALSE(BeatsInSweepOrder(empty, a));
  EXPECT_FALSE(BeatsInSweepOrder(a, a));
  TileWinner b = a;
  b.ncc = 0.995f;
  EXPECT_TRUE(BeatsInSweepOrder(b, a));
  // Equal NCCs: the smaller k, then the earlier neighbour, then the earlier pixel (row-major).
  b = a;
  b.offset = -3;
  b.neighbour = 1;
  b.row = 9;
  EXPECT_TRUE(BeatsInSweepOrder(b, a));
  EXPECT_FALSE(BeatsInSweepOrder(a, b));
  b = a;
  b.neighbour = 0;
  b.row = 9;
  EXPECT_TRUE(BeatsInSweepOrder(b, a));
  b = a;
  b.row = 4;
  b.col = 90;
  EXPECT_TRUE(BeatsInSweepOrder(b, a));
  b = a;
  b.col = 6;
  EXPECT_TRUE(BeatsInSweepOrder(b, a));
}

// One 4x1 tile, two neighbours: pixel 0 is the best match of neighbour 0 alone (neighbour 1
// sees it and does not match), pixel 2 a lower one of both, pixel 3 one of neighbour 0 that
// neighbour 1 does not see (NaN).
TEST(SweepKernel, WinnersNeedTheRequiredMatches) {
  const TileGrid tiles = TileGrid::Make(4, 1, 100);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> first = {0.999f, 0.5f, 0.985f, 0.992f};
  const std::vector<float> second = {0.97f, 0.995f, 0.99f, nan};
  const std::vector<int32_t> face = {10, 11, 12, 13};
  const auto winner = [&](const std::vector<float>& a, const std::vector<float>& b, int required,
                          bool strict = false) {
    std::vector<TileWinner> best(1);
    const WinnerRule rule{/*threshold=*/0.98f, required, /*support=*/0.98f, strict,
                          /*must_move=*/false};
    UpdateTileWinners(tiles, /*offset=*/-1, {a.data(), b.data()}, {}, face.data(), nullptr, rule,
                      &best);
    return best[0];
  };
  // The paper's rule: the highest NCC of any neighbour.
  TileWinner w = winner(first, second, 1);
  EXPECT_EQ(w.ncc, 0.999f);
  EXPECT_EQ(w.col, 0);
  EXPECT_TRUE(w.matched.empty());
  // Two: pixel 3, which only neighbour 0 sees, beats pixel 2.
  w = winner(first, second, 2);
  EXPECT_EQ(w.ncc, 0.992f);
  EXPECT_EQ(w.col, 3);
  EXPECT_EQ(w.neighbour, 0);
  EXPECT_TRUE(w.matched.empty());
  // Two, strict: neighbour 1 does not see pixel 3, so pixel 2 wins, through neighbour 1's NCC,
  // with neighbour 0 listed as matched; likewise without pixel 3.
  for (const bool strict : {true, false}) {
    std::vector<float> first_maybe_3 = first;
    if (!strict) first_maybe_3[3] = nan;
    w = winner(first_maybe_3, second, 2, strict);
    EXPECT_EQ(w.ncc, 0.99f) << strict;
    EXPECT_EQ(w.col, 2) << strict;
    EXPECT_EQ(w.neighbour, 1) << strict;
    EXPECT_EQ(w.face, 12) << strict;
    EXPECT_EQ(w.matched, std::vector<int>{0}) << strict;
  }
  // No pixel above the threshold in both neighbours that see it: no winner.
  const std::vector<float> low = {0.97f, 0.97f, 0.97f, 0.97f};
  EXPECT_LT(winner(first, low, 2).neighbour, 0);
  // A neighbour that sees nothing: the other alone decides, unless strict.
  const std::vector<float> unseen(4, nan);
  EXPECT_EQ(winner(first, unseen, 2).col, 0);
  EXPECT_LT(winner(first, unseen, 2, /*strict=*/true).neighbour, 0);
}

// Winners that must move: k = 0 never competes, and a pixel at k != 0 must beat the same
// neighbour's NCC at k = 0 there (undefined at k = 0: nothing to beat).
TEST(SweepKernel, WinnersMustBeatTheUnsweptMesh) {
  const TileGrid tiles = TileGrid::Make(4, 1, 100);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> swept = {0.999f, 0.99f, 0.985f, 0.982f};
  const std::vector<float> unswept = {0.9995f, 0.99f, 0.5f, nan};
  const std::vector<int32_t> face = {10, 11, 12, 13};
  WinnerRule rule{/*threshold=*/0.98f, /*required_matches=*/1, /*support=*/0.8f,
                  /*strict=*/false, /*must_move=*/true};
  std::vector<TileWinner> best(1);
  // Pixel 0 matches better unswept, pixel 1 no better: pixel 2 wins, not the higher 0 or 1.
  UpdateTileWinners(tiles, /*offset=*/2, {swept.data()}, {unswept.data()}, face.data(), nullptr,
                    rule, &best);
  EXPECT_EQ(best[0].col, 2);
  EXPECT_EQ(best[0].offset, 2);
  // Where k = 0 is undefined (pixel 3), any offset above the threshold may win.
  best.assign(1, TileWinner());
  const std::vector<float> only_3 = {nan, nan, nan, 0.982f};
  UpdateTileWinners(tiles, /*offset=*/-1, {only_3.data()}, {unswept.data()}, face.data(), nullptr,
                    rule, &best);
  EXPECT_EQ(best[0].col, 3);
  // The paper's rule: pixel 0, and k = 0 itself may be passed.
  rule.must_move = false;
  best.assign(1, TileWinner());
  UpdateTileWinners(tiles, /*offset=*/2, {swept.data()}, {}, face.data(), nullptr, rule, &best);
  EXPECT_EQ(best[0].col, 0);
  // Which offsets compete.
  PreparedSweep prep;
  prep.offsets = SweepOffsets(6);  // -2..2
  EXPECT_EQ(CompetingOffsets(prep, rule), (std::vector<int>{-2, -1, 0, 1, 2}));
  rule.must_move = true;
  EXPECT_EQ(CompetingOffsets(prep, rule), (std::vector<int>{-2, -1, 1, 2}));
}

TEST(SweepKernel, WinnerRuleTakesTheOptions) {
  SweepOptions options;
  EXPECT_EQ(options.min_matching_neighbours, 2);
  EXPECT_TRUE(WinnerRule::For(options, 2).strict);  // the defaults
  EXPECT_TRUE(WinnerRule::For(options, 2).must_move);
  EXPECT_EQ(WinnerRule::For(options, 2).required_matches, 2);
  EXPECT_EQ(WinnerRule::For(options, 1).required_matches, 1);
  options.min_matching_neighbours = 0;  // what an older coordinator's message holds
  EXPECT_EQ(WinnerRule::For(options, 2).required_matches, 1);
  options.min_matching_neighbours = 3;
  options.ncc_threshold = 0.95;
  options.support_ncc = 0.7;
  options.strict_support = true;
  options.winners_must_move = false;  // what an older coordinator's message holds
  const WinnerRule rule = WinnerRule::For(options, 34);
  EXPECT_EQ(rule.required_matches, 3);
  EXPECT_EQ(rule.threshold, 0.95f);
  EXPECT_EQ(rule.support, 0.7f);
  EXPECT_TRUE(rule.strict);
  EXPECT_FALSE(rule.must_move);
  options.strict_support = false;
  EXPECT_FALSE(WinnerRule::For(options, 2).strict);
}

TEST(SweepKernel, PreparedSweepStatsCountsTheHypotheses) {
  PreparedSweep prep = ThreeNeighbours();
  prep.camera.view.intrinsics.width = 320;
  prep.camera.view.intrinsics.height = 240;
  prep.pyramid_level = 1;
  prep.alpha = 0.02;
  prep.median_depth = 2.5;
  prep.offsets = SweepOffsets(20);
  prep.tiles = TileGrid::Make(320, 240, 100);
  const SweepStats stats = PreparedSweepStats(prep);
  EXPECT_EQ(stats.image_width, 320);
  EXPECT_EQ(stats.image_height, 240);
  EXPECT_EQ(stats.pyramid_level, 1);
  EXPECT_EQ(stats.alpha, 0.02);
  EXPECT_EQ(stats.median_depth, 2.5);
  EXPECT_EQ(stats.num_offsets, 19);
  EXPECT_EQ(stats.num_neighbours, 3);
  EXPECT_EQ(stats.tiles_x, 3);
  EXPECT_EQ(stats.tiles_y, 2);
  EXPECT_EQ(stats.hypotheses, int64_t{320} * 240 * 19 * 3);
  EXPECT_EQ(stats.valid_hypotheses, 0);
  EXPECT_EQ(stats.total_s, 0);
}

}  // namespace
}  // namespace ms
