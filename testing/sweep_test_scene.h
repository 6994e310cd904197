// Synthetic scenes for the sweep's tests and benchmark: a textured pyramid on a textured ground
// plane (the paper's simulated dataset: 2 x 2 base, 0.3 high; sweep/pyramid_geometry.h), seen
// from three cameras looking down, rendered analytically (each pixel's rays cast against the
// exact surface, textured with procedural multi-scale value noise, 2 x 2 supersampled).
// Test-only (ms_sweep_test_scene): linked by tests and benchmarks, never by `manisweep`.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "mesh/mesh.h"
#include "sweep/pyramid_geometry.h"
#include "sweep/sweep_kernel.h"

namespace ms {

struct PyramidSceneOptions {
  int width = 160, height = 120;  // every camera's image size
  double focal_px = 150;          // at 160 px wide; scaled with width
  // Apex height above the ground (base: [-1, 1]^2 at z = 0; sweep/pyramid_geometry.h).
  double pyramid_height = kPyramidHeight;
  double texture_contrast = 1;  // texture = 0.5 + contrast * (noise - 0.5); 0 = blank
  int supersample = 2;          // rays per pixel per axis
  double noise_stddev = 0;      // independent Gaussian noise per camera (fixed seeds)
};

struct PyramidScene {
  std::vector<SweepCamera> cameras;  // 0 = C, 1 and 2 its neighbours; ids 0, 1, 2
  Mesh truth;                        // the pyramid and the ground around it, triangulated
  // Height of the true surface at (x, y).
  double Height(double x, double y) const;
  // Euclidean distance from p to the true surface.
  double Distance(const Eigen::Vector3d& p) const;
  double pyramid_height = kPyramidHeight;
};

PyramidScene MakePyramidScene(const PyramidSceneOptions& options = {});

// A flat square [-half, half]^2 at height z, split into cells x cells x 2 triangles facing +z.
Mesh MakeFlatSquare(double z, double half_size, int cells);

// Camera 0's sweep job: neighbours 1 and 2, the part of `mesh` camera 0 sees, default options.
SweepJob MakePyramidSweepJob(const PyramidScene& scene, const Mesh& mesh);

// The benchmarks' job: a width x height (0: 3/4 width) pyramid with image noise 0.01, swept from
// the flat square at half its height (16 x 16 cells).
SweepJob MakeBenchmarkSweepJob(int width, int height = 0);

// The parity tests' small jobs (sweep/*_sweep_test.cc): MakePyramidSweepJob with a window and
// tiles for 160 x 120 images (sigma 4 px, 10 px tiles instead of the defaults for megapixels).
SweepJob MakeSmallSweepJob(const PyramidScene& scene, const Mesh& mesh);

// A valid small job (a 40×30 pyramid scene without supersampling, a flat square as its mesh)
// for the tests that break it one field at a time.
SweepJob MakeTinyValidSweepJob();

// The default pyramid scene with sensor noise 0.01, independent per camera (built once).
const PyramidScene& NoisyPyramidScene();

// The true surface plus a small square floating at z = 0.9 above one side: it hides ground that
// C sees from a neighbour, so the shadow-map test matters.
Mesh TruthWithOccluder(const PyramidScene& scene);

// Uniform noise in [0, 1] blurred by a Gaussian of sigma 1.5 px (CV_32F), for NCC tests.
cv::Mat BlurredNoiseImage(int width, int height, uint64_t seed);

// A view at `center` looking at `target`, image y pointing along -world_y as seen from above.
View LookAtView(const Eigen::Vector3d& center, const Eigen::Vector3d& target, int width, int height,
                double focal_px);

}  // namespace ms
