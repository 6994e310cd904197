// The GLSL kernel of the photometric gradient (photometric_gradient.h), for workers with a GPU:
// the mesh is rasterised from both cameras by gl::MeshRenderer, and four compute passes
// (shaders/refine_*.comp) sample the neighbour through the mesh, filter the window's sums,
// take each pixel's ZNCC and its coefficients, filter those, and apply the chain rule per pixel.
// What comes back per pixel (face, dE/dd / cos, parallax^2 / cos^2, two barycentric weights,
// 1 - ZNCC) is summed per face and per vertex on the CPU in pixel order, as the fast CPU kernel
// does, so the result is deterministic. Float on the GPU, the statistics in double; agrees with
// the reference to the tolerances of refine_test.
#pragma once

#include <memory>

#include "gl/context.h"
#include "refine/photometric_gradient.h"

namespace ms {

class GlslPairGradient {
 public:
  // Creates its own GL context (current only while computing, so any one thread may call
  // Compute). Throws InternalError if no GL 4.3 context can be made or a shader does not compile.
  explicit GlslPairGradient(const gl::GlContextOptions& context = {});
  // The same on a context already made (current or not on this thread); takes it over.
  explicit GlslPairGradient(std::unique_ptr<gl::GlContext> context);
  ~GlslPairGradient();
  GlslPairGradient(const GlslPairGradient&) = delete;
  GlslPairGradient& operator=(const GlslPairGradient&) = delete;

  // Not thread-safe: one call at a time.
  PairGradient Compute(const Mesh& mesh, const RefineView& reference, const RefineView& neighbour,
                       const RefineOptions& options);
  const gl::GlInfo& gl_info() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ms
