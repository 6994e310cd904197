// The GLSL mesh-sweeping kernel (paper section 2.2; docs/design/sweep.md "The GLSL kernel"): the
// same hypotheses, conventions and tie-breaking as the C++ reference (sweep/reference_sweep.h), on
// the GPU through a headless EGL context (NVIDIA's driver, or Mesa's llvmpipe without a GPU).
//
// Per batch of offsets k (texture arrays, one layer per offset): one instanced draw whose
// geometry shader sweeps every facet renders all swept meshes M_k from C (world position + face)
// and one per neighbour renders their shadow maps; then, per offset and neighbour, compute
// passes reproject the neighbour's image into C (shadow-map occlusion, bilinear from
// texelFetch), blur the six NCC sums along rows and columns and evaluate the NCC; a last pass
// per batch keeps every tile's best pixel. Only the tile winners are read back. No GL type
// appears here.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "gl/context.h"
#include "sweep/sweep_kernel.h"

namespace ms {

// How the two blur passes are compiled.
enum class GlslBlurVariant {
  kAuto,      // kUnrolled on a CPU rasterizer (llvmpipe), kLoops on a GPU
  kLoops,     // plain tap loops, one output per invocation, row-major sums (GPUs)
  kUnrolled,  // fully unrolled, BLOCK outputs per invocation, transposed sums (CPU rasterizers)
};

struct GlslSweepKernelOptions {
  gl::GlContextOptions context;  // backend etc. (used when the kernel creates its own context)
  GlslBlurVariant blur = GlslBlurVariant::kAuto;
  // Outputs per invocation of the blur passes; 0 = the variant's default (1 for loops, 16
  // unrolled).
  int blur_block = 0;
  // GPU memory for one batch's textures (C's render and reprojections, shadow maps, NCC maps,
  // plus the per-job ones); offsets are batched so that a batch fits (at least one offset per
  // batch). 0 = 1 GiB on a GPU, 128 MiB on a CPU rasterizer (where batching gains nothing).
  int64_t max_batch_bytes = 0;
  // At most this many offsets per batch; 0 = as many as fit max_batch_bytes.
  int max_batch_offsets = 0;
  // GPU timestamps at stage boundaries so SweepStats has per-stage GPU times (no waits);
  // false leaves only total and prepare times.
  bool time_stages = true;
  // Extra "#define NAME VALUE" lines for every sweep shader (tuning experiments, tests).
  std::vector<std::string> shader_defines;
  void Check() const;  // throws InputError naming the field
};

// Per-stage images of one offset, for comparisons with the reference (tests, debugging).
// Captured when GlslSweepKernel::Run is given a capture; all at the swept resolution.
struct GlslSweepCapture {
  int offset = 0;                    // k to capture (must be one of the job's offsets)
  cv::Mat world;                     // CV_32FC3 world position of M_k seen from C (0 where empty)
  cv::Mat depth;                     // CV_32F its camera z in C (from world), +inf where empty
  cv::Mat face;                      // CV_32S face of the job mesh (-1 where empty)
  std::vector<cv::Mat> shadow;       // per neighbour: CV_32F camera z of M_k, +inf where empty
  std::vector<cv::Mat> reprojected;  // per neighbour: CV_32F I_k^j, 0 where invalid
  std::vector<cv::Mat> mask;         // per neighbour: CV_8U, 255 where valid
  std::vector<cv::Mat> ncc;          // per neighbour: CV_32F, NaN where undefined
};

class GlslSweepKernel : public SweepKernel {
 public:
  // Creates its own GL context (options.context), current on the calling thread, and compiles
  // the shaders. Throws InternalError if no GL 4.3 context can be created or a shader does not
  // compile (the driver's log, with the offending source lines), InputError for bad options.
  explicit GlslSweepKernel(const GlslSweepKernelOptions& options = {});
  // Uses `context` (which must outlive the kernel) instead of creating one.
  GlslSweepKernel(const gl::GlContext& context, const GlslSweepKernelOptions& options = {});
  ~GlslSweepKernel() override;
  GlslSweepKernel(const GlslSweepKernel&) = delete;
  GlslSweepKernel& operator=(const GlslSweepKernel&) = delete;

  // Throws InputError for a bad job (CheckSweepJob), or for one beyond the driver's limits
  // (texture size) or the kernel's (2^24 faces). Call from one thread at a time; the context is
  // made current on it.
  SweepResult Run(const SweepJob& job) override;
  // The same, also filling `capture` (its offset set by the caller) with that offset's images.
  SweepResult Run(const SweepJob& job, GlslSweepCapture* capture);
  std::string Name() const override { return "glsl"; }

  const gl::GlInfo& gl_info() const;
  // The variant in use and its block size (after kAuto / 0 are resolved).
  GlslBlurVariant blur_variant() const;
  int blur_block() const;
  // Offsets per batch and GPU bytes of one batch's textures plus the per-job ones, for a job.
  struct MemoryPlan {
    int offsets_per_batch = 1;
    int64_t per_offset_bytes = 0;  // C's render + shadow maps + NCC maps of one offset
    int64_t fixed_bytes = 0;       // images, reprojection and blur buffers, tile records
  };
  MemoryPlan PlanMemory(const PreparedSweep& prep, const WinnerRule& rule) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ms
