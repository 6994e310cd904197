// The parity check of a sweep kernel against the C++ reference (docs/design/sweep.md): the same
// tile winners (pixel and offset) in nearly every tile, and where they agree the same face and
// cameras, NCC and position within tolerance. Test-only, header-only (gtest).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <utility>

#include "sweep/sweep_kernel.h"

namespace ms {

// Tolerances: `min_same` of the reference's tiles with the same winner, NCC within `max_ncc`,
// position within `max_position` x depth.
struct ParityBounds {
  double min_same = 0.95, max_ncc = 1e-3, max_position = 1e-5;
};

inline void ExpectSameWinners(const SweepResult& ref, const SweepResult& gl, double depth,
                              const std::string& label, const ParityBounds& bounds = {}) {
  std::map<std::pair<float, float>, const SweepPoint*> by_pixel;
  for (const SweepPoint& p : ref.points) by_pixel[{p.pixel.x(), p.pixel.y()}] = &p;
  int same = 0;
  double worst_ncc = 0, worst_position = 0;
  for (const SweepPoint& p : gl.points) {
    auto it = by_pixel.find({p.pixel.x(), p.pixel.y()});
    if (it == by_pixel.end() || it->second->offset != p.offset) continue;
    const SweepPoint& r = *it->second;
    ++same;
    worst_ncc = std::max<double>(worst_ncc, std::abs(p.ncc - r.ncc));
    worst_position = std::max(worst_position, (p.position - r.position).norm() / depth);
    EXPECT_EQ(p.face, r.face);
    EXPECT_EQ(p.cameras, r.cameras);
  }
  std::printf(
      "[%s] %zu points (reference %zu), %d at the same pixel and offset; worst NCC "
      "difference %.1e, worst position difference %.1e x depth\n",
      label.c_str(), gl.points.size(), ref.points.size(), same, worst_ncc, worst_position);
  const double n = static_cast<double>(ref.points.size());
  EXPECT_NEAR(static_cast<double>(gl.points.size()), n, std::max(2.0, 0.02 * n));
  EXPECT_GE(same, bounds.min_same * n);
  EXPECT_LT(worst_ncc, bounds.max_ncc);
  EXPECT_LT(worst_position, bounds.max_position);
  EXPECT_EQ(gl.stats.hypotheses, ref.stats.hypotheses);
  EXPECT_EQ(gl.stats.num_offsets, ref.stats.num_offsets);
  EXPECT_EQ(gl.stats.tiles_x, ref.stats.tiles_x);
  EXPECT_NEAR(static_cast<double>(gl.stats.covered_pixels), ref.stats.covered_pixels,
              0.002 * ref.stats.covered_pixels);
  EXPECT_NEAR(static_cast<double>(gl.stats.valid_hypotheses), ref.stats.valid_hypotheses,
              0.01 * ref.stats.valid_hypotheses);
}

}  // namespace ms
