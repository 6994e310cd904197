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

// ---- Test-only: defined in app/pyramid_scene_files.cc, library ms_default_scene (what the
// multi-process tests link); not in the manisweep binary. ----

struct PyramidSceneFileOptions {
  int width = 640, height = 480;  // image size of every camera
  double noise_stddev = 0.01;     // Gaussian pixel noise (images in [0, 1])
};

// A smaller pyramid scene for the multi-process tests (the sweep's test renderer,
// sweep/sweep_test_scene.h, three cameras): images/pyramid_<i>.png (16-bit gray), scene.h5 (3
// views; the 4 base corners as sparse points seen by every view: the paper's start), gt.ply (the
// true surface). Returns the path of scene.h5.
std::string WritePyramidSceneFiles(const std::string& directory,
                                   const PyramidSceneFileOptions& options);

}  // namespace ms::app
