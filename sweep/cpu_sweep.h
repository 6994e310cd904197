// The fast CPU sweep kernel (docs/sweep.md "The fast CPU kernel"): the reference's hypotheses and
// tile-best rule (sweep/reference_sweep.h) computed for speed:
// - span rasterisation of 1/z and face ids in float (sweep/span_raster.h), the same coverage;
// - reprojection through C's 1/z in float, branch-free so that it vectorises (AVX2 gathers);
// - the Gaussian-weighted NCC by Deriche's recursive Gaussian in O(1) per pixel, fused into two
//   streaming passes (sweep/windowed_ncc.h);
// - offsets split among the threads OpenCV is allowed (cv::setNumThreads; the worker's
//   --threads), winners merged in offset order so the result does not depend on the split.
// The winning point is placed in double precision: C's ray through the pixel centre meets the
// plane of the swept facet, which is where the reference's interpolation puts it.
#pragma once

#include <string>

#include "sweep/sweep_kernel.h"

namespace ms {

class CpuSweepKernel : public SweepKernel {
 public:
  SweepResult Run(const SweepJob& job) override;
  std::string Name() const override { return "cpu"; }
};

}  // namespace ms
