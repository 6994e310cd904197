#include "manifold/min_cut.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace ms::manifold_detail {
namespace {

// What cutting `side` (1: source side) from the rest costs.
int64_t CutCost(const std::vector<uint8_t>& side, const std::vector<int64_t>& from_source,
                const std::vector<int64_t>& to_sink, const std::vector<CutEdge>& edges) {
  int64_t cost = 0;
  for (size_t i = 0; i < side.size(); ++i) cost += side[i] ? to_sink[i] : from_source[i];
  for (const CutEdge& e : edges) {
    if (side[e.a] && !side[e.b]) cost += e.a_to_b;
    if (side[e.b] && !side[e.a]) cost += e.b_to_a;
  }
  return cost;
}

// On random graphs small enough to try every partition, the returned side costs the minimum,
// and among the minimum cuts it is the smallest source side (the residual reach of the source):
// every other minimum cut's source side contains it.
TEST(MinCut, FindsTheSmallestMinimumCutOfSmallGraphs) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> capacity(0, 6), node_count(1, 9);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = node_count(rng);
    std::vector<int64_t> from_source(n), to_sink(n);
    for (int i = 0; i < n; ++i) {
      from_source[i] = capacity(rng) < 3 ? 0 : capacity(rng);
      to_sink[i] = capacity(rng) < 3 ? 0 : capacity(rng);
    }
    std::vector<CutEdge> edges;
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) {
        if (capacity(rng) < 3) edges.push_back({a, b, capacity(rng), capacity(rng)});
      }
    }
    const std::vector<uint8_t> side = SourceSideOfMinCut(from_source, to_sink, edges);
    ASSERT_EQ(side.size(), static_cast<size_t>(n));
    const int64_t found = CutCost(side, from_source, to_sink, edges);
    int64_t best = INT64_MAX;
    std::vector<std::vector<uint8_t>> minimal;
    for (uint32_t mask = 0; mask < (1u << n); ++mask) {
      std::vector<uint8_t> other(n);
      for (int i = 0; i < n; ++i) other[i] = (mask >> i) & 1;
      const int64_t cost = CutCost(other, from_source, to_sink, edges);
      if (cost < best) {
        best = cost;
        minimal.clear();
      }
      if (cost == best) minimal.push_back(other);
    }
    ASSERT_EQ(found, best) << "trial " << trial;
    for (const std::vector<uint8_t>& other : minimal) {
      for (int i = 0; i < n; ++i) ASSERT_LE(side[i], other[i]) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace ms::manifold_detail
