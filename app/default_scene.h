// The embedded default scene of `manisweep reconstruct` (run without --input): the paper's
// downward pyramid (`manisweep synth pyramid-down`, fewer and smaller views so the demo is
// quick), made on the fly, so a new user sees the whole pipeline work at once and how close
// it gets to the ground truth.
#pragma once

#include <string>

namespace ms::app {

// Writes the default scene into `directory` (created; images/, scene.h5, gt.ply, ...) and
// returns the scene file to reconstruct. Renders with OpenGL through EGL (llvmpipe without a
// GPU).
std::string MakeDefaultScene(const std::string& directory);

}  // namespace ms::app
