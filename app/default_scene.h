// The embedded default scene of `manisweep reconstruct` (run without --input): a synthetic
// textured pyramid made on the fly, so a new user sees the whole pipeline work at once.
//
// Until `manisweep synth` (tools/) lands, the scene comes from the sweep's test renderer
// (worker/sweep_test_scene.h: the paper's pyramid, 2 x 2 base, 0.3 high, three cameras looking
// down); MakeDefaultScene is the one place to switch to synth's "pyramid-down".
#pragma once

#include <string>

namespace ms::app {

// Writes the default scene into `directory` (created) and returns the scene file to
// reconstruct.
std::string MakeDefaultScene(const std::string& directory);

struct PyramidSceneFileOptions {
  int width = 640, height = 480;  // image size of every camera
  double noise_stddev = 0.01;     // Gaussian pixel noise (images in [0, 1])
};

// The pyramid scene as files: images/pyramid_<i>.png (16-bit gray), scene.h5 (3 views; the 4
// base corners as sparse points seen by every view: the paper's start), gt.ply (the true
// surface). Returns the path of scene.h5. Also used by the multi-process tests.
std::string WritePyramidSceneFiles(const std::string& directory,
                                   const PyramidSceneFileOptions& options);

}  // namespace ms::app
