// The fast CPU sweep kernel (docs/design/sweep.md "The fast CPU kernel"): the reference's
// hypotheses and tile-best rule (sweep/reference_sweep.h) computed for speed:
// - span rasterisation of 1/z and face ids in float (sweep/span_raster.h), the same coverage;
// - reprojection through C's 1/z in float, branch-free so that it vectorises (AVX2 gathers);
// - the Gaussian-weighted NCC by Deriche's recursive Gaussian in O(1) per pixel, fused into two
//   streaming passes (sweep/windowed_ncc.h);
// - offsets split among the threads OpenCV is allowed (cv::setNumThreads; the worker's
//   --threads), winners merged in offset order so the result does not depend on the split.
// The winning point is placed in double precision: C's ray through the pixel centre meets the
// plane of the swept facet, which is where the reference's interpolation puts it.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "base/large_buffer.h"
#include "sweep/span_raster.h"
#include "sweep/sweep_kernel.h"
#include "sweep/windowed_ncc.h"

namespace ms {

// One swept mesh at a time, as the CPU kernel computes it: C's raster and the neighbours' shadow
// maps, then per neighbour the reprojection and the NCC map. The kernel runs one per thread;
// the photo-consistency measure (tools/consistency.h) uses offset 0, the mesh itself.
class CpuSweepSlab {
 public:
  // `job` and `prep` (PrepareSweep(job)) must outlive the slab.
  CpuSweepSlab(const SweepJob& job, const PreparedSweep& prep);
  // Renders the job's mesh swept by offset k from C and from every neighbour.
  void Render(int k);
  // Reprojects neighbour j (an index into prep.neighbours) into C through the rendered surface.
  void Reproject(int j);
  // NCC of C's image against the last reprojection (row-major at the swept resolution, NaN where
  // undefined); returns the number of defined pixels.
  int64_t Ncc(float* out);
  // The last reprojection: the neighbour's image minus 0.5 where valid (0 elsewhere), and the
  // mask of valid pixels (1 or 0), row-major at the swept resolution.
  const LargeBuffer<float>& reprojected() const { return J_; }
  const LargeBuffer<float>& valid() const { return mask_; }
  // C's face per pixel of the last rendering (-1: nothing drawn) and their count.
  const LargeBuffer<int32_t>& faces() const { return camera_raster_.face(); }
  int64_t CoveredPixels() const;

 private:
  const SweepJob& job_;
  const PreparedSweep& prep_;
  std::vector<Eigen::Vector3d> normals_;
  SpanRasterizer camera_raster_;
  std::vector<SpanRasterizer> shadow_maps_;
  WindowedNcc ncc_;
  LargeBuffer<float> J_, mask_;
};

// Where view's ray through `pixel` meets the plane of `facet` (world coordinates), kept within
// the facet's depth range (camera z, and beyond `near`): a winner's pixel centre is inside its
// rasterised facet, but where the facet grazes the ray, rounding can put the plane's crossing
// far outside the facet, and so outside the depths the job can sweep (the coordinator rejects
// such a point, coordinator/insertion_batch.h). The point stays on the pixel's ray.
Eigen::Vector3d PixelRayOnFacet(const View& view, const Eigen::Vector2d& pixel,
                                const std::array<Eigen::Vector3d, 3>& facet, double near);

class CpuSweepKernel : public SweepKernel {
 public:
  SweepResult Run(const SweepJob& job) override;
  std::string Name() const override { return "cpu"; }
};

}  // namespace ms
