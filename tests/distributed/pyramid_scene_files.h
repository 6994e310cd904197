// Test-only (the multi-process tests; never in the manisweep binary): the sweep's analytic
// pyramid test scene written as scene files.
#pragma once

#include <string>

namespace ms::testing {

struct PyramidSceneFileOptions {
  int width = 640, height = 480;  // image size of every camera
  double noise_stddev = 0.01;     // Gaussian pixel noise (images in [0, 1])
};

// A smaller pyramid scene for the multi-process tests (the sweep's test renderer,
// testing/sweep_test_scene.h, three cameras): images/pyramid_<i>.png (16-bit gray), scene.h5 (3
// views; the 4 base corners as sparse points seen by every view: the paper's start), gt.ply (the
// true surface). Returns the path of scene.h5.
std::string WritePyramidSceneFiles(const std::string& directory,
                                   const PyramidSceneFileOptions& options);

}  // namespace ms::testing
