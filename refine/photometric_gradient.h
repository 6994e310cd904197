// The photometric energy of a mesh for one pair of cameras and its gradient with respect to the
// mesh's vertices (docs/design/refine.md), in the image-domain form of Vu et al. (PAMI 2012) after
// Pons et al. (IJCV 2007): the neighbour's image is reprojected into the reference camera
// through the mesh, and
//   E = sum over the reference's pixels p with a defined ZNCC of (1 - ZNCC_p),
// ZNCC_p over a Gaussian window. Each pixel's depth along its ray depends on the vertices of
// the face it sees; the chain rule goes image value -> depth along the ray -> vertex position:
//   dE/dv = sum_p dE/dJ(p) * dJ/dd(p) * phi_v(p) * n_f / (n_f . r_p),
// phi_v the barycentric weight, n_f the face's normal, r_p the unit ray. Changes of visibility
// and of the set of covered pixels are ignored (they are not differentiable). This is the exact
// C++ reference: double precision, rasterised by the sweep's software rules; the fast CPU kernel
// computes the same in float maps (photometric_gradient_fast.cc).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "mesh/mesh.h"
#include "refine/refine_options.h"
#include "scene/camera.h"

namespace ms {

// A camera at one scale: a pinhole view (no distortion) and its gray image in [0, 1] (CV_64F),
// of the view's size.
struct RefineView {
  int camera = -1;
  View view;
  cv::Mat image;
};

// What one pair adds up; the refiner sums pairs in a fixed order.
struct PairGradient {
  double energy = 0;   // sum of (1 - ZNCC) over defined pixels
  int64_t pixels = 0;  // pixels with a defined ZNCC
  // Per vertex: dE/dv; H_v = sum_p phi_v |d(pixel in the neighbour)/dd|^2 / (n_f . r_p)^2, the
  // squared parallax rate (pixels^2 per unit^2) that scales the step; W_v = sum_p phi_v.
  std::vector<Eigen::Vector3d> gradient;
  std::vector<double> parallax_rate2;
  std::vector<double> weight;

  // Mean (1 - ZNCC) over the defined pixels (0 without any).
  double MeanEnergy() const { return pixels > 0 ? energy / static_cast<double>(pixels) : 0; }
  void Resize(size_t vertices);
  void Add(const PairGradient& other);  // sums, vertex by vertex
};

// The kernels (refine/gradient_kernel.h picks one by --refine.kernel; glsl_gradient.h is the
// GPU's): `reference` and `neighbour` are at the same scale. Faces of `mesh` are drawn as they
// are (both orientations); the reference's pixel sees the nearest.

// The exact reference: double precision throughout, the sweep's SoftwareRasterizer (world
// position per pixel), OpenCV's separable Gaussian in double, the chain rule pixel by pixel.
PairGradient ComputePairGradientReference(const Mesh& mesh, const RefineView& reference,
                                          const RefineView& neighbour,
                                          const RefineOptions& options);

// The fast CPU kernel: the same pixels and formulas with the sweep's span rasteriser (face ids
// and 1/z in float; each pixel's point is its ray's intersection with the face's plane, in
// double), the window's sums as float maps, and the chain rule summed per face before per
// vertex. Its buffers are pooled between calls. Agrees with the reference to float rounding (energy
// within 1e-4 relative on the test scenes: refine_test); not bit-identical to it.
PairGradient ComputePairGradientFast(const Mesh& mesh, const RefineView& reference,
                                     const RefineView& neighbour, const RefineOptions& options);

}  // namespace ms
