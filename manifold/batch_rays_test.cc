#include "manifold/batch_rays.h"

#include <gtest/gtest.h>

namespace ms::manifold_detail {
namespace {

TEST(BatchRays, UntouchedRaysReadTheDefaultsAndTouchedOnesKeepTheirState) {
  BatchRays rays;
  rays.Reset(5, 7);  // 5 rays, counted up to part 7
  for (int32_t id = 0; id < 5; ++id) {
    const BatchRays::State s = rays.Get(id);
    EXPECT_EQ(s.reach, 2.0f);
    EXPECT_EQ(s.counted, 7u);
    EXPECT_EQ(s.marked, 0u);
  }
  BatchRays::State& touched = rays.Touch(3);
  EXPECT_EQ(touched.counted, 7u) << "a first touch starts from the defaults";
  touched.reach = 0.25f;
  touched.marked = 9;
  EXPECT_EQ(rays.Touch(3).reach, 0.25f) << "a second touch finds the same state";
  EXPECT_EQ(rays.Get(3).marked, 9u);
  EXPECT_EQ(rays.Get(2).marked, 0u);

  // Rays traced in part 9 join counted up to it; the old ones keep theirs.
  rays.AddTraced(8, 9);
  for (int32_t id = 5; id < 8; ++id) EXPECT_EQ(rays.Get(id).counted, 9u);
  EXPECT_EQ(rays.Get(0).counted, 7u);
  EXPECT_EQ(rays.Get(3).reach, 0.25f);

  rays.Reset(8, 12);  // everything counted again
  for (int32_t id = 0; id < 8; ++id) {
    EXPECT_EQ(rays.Get(id).counted, 12u);
    EXPECT_EQ(rays.Get(id).reach, 2.0f);
  }
}

}  // namespace
}  // namespace ms::manifold_detail
