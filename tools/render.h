// Shaded pictures of meshes from a scene's camera (`manisweep render`): what the paper shows
// as "untextured reconstruction". Faces are lit from the camera; faces seen from behind (their
// normal points away from the camera) are tinted red, which shows an inside-out surface.
#pragma once

#include <opencv2/core.hpp>

#include "gl/context.h"
#include "mesh/mesh.h"
#include "scene/camera.h"

namespace ms {

struct ShadedRenderOptions {
  int max_size = 1200;  // longest image side; the view is scaled down to fit (0 = as is)
  void Check() const;   // throws InputError naming the field
};

// The view scaled so its longest side is at most max_size (intrinsics scaled exactly).
View ScaledView(const View& view, int max_size);

// CV_8UC3 (BGR) picture of `mesh` seen from `view`.
cv::Mat RenderShaded(const gl::GlContext& context, const Mesh& mesh, const View& view,
                     const ShadedRenderOptions& options = {});

}  // namespace ms
