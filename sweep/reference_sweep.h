// The C++ reference of the mesh-sweeping kernel: exactly the paper's math (section 2.2) on the
// CPU with OpenCV, written for clarity and as the yardstick of the GLSL kernel
// (docs/design/sweep.md).
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "sweep/software_raster.h"
#include "sweep/sweep_kernel.h"

namespace ms {

class ReferenceSweepKernel : public SweepKernel {
 public:
  SweepResult Run(const SweepJob& job) override;
  std::string Name() const override { return "reference"; }
};

// ---- The steps, exposed for tests and for comparison with the GLSL kernel. ----

// Unit normal of every face of the mesh (zero for a degenerate face).
std::vector<Eigen::Vector3d> FaceNormals(const Mesh& mesh);

// Mesh M_k as a triangle soup: every facet moved on its own (SweepVertex with the facet's
// normal), so facets sharing a vertex may come apart.
std::vector<std::array<Eigen::Vector3d, 3>> SweepFacets(const Mesh& mesh,
                                                        const std::vector<Eigen::Vector3d>& normals,
                                                        const Eigen::Vector3d& center,
                                                        double alpha_k);

// Renders the triangle soup into `raster` (cleared first); face ids are the soup's indices.
void RenderSoup(const std::vector<std::array<Eigen::Vector3d, 3>>& soup,
                SoftwareRasterizer* raster);

// I_k^j: the neighbour's image reprojected into C through the surface C sees (`camera_raster`,
// with world positions), with the neighbour's depth of the same surface as shadow map. A pixel
// is valid (mask 255) if C sees a surface there, the point is in front of the neighbour, its
// projection (u, v) lies within [0.5, W-0.5] x [0.5, H-0.5] (no texture clamping needed), and
// its depth is at most (1 + occlusion_tolerance) x the shadow map's depth at texel
// (floor(u), floor(v)). The value is the bilinear sample at (u - 0.5, v - 0.5) in texel indices.
// `reprojected` is CV_32F (0 where invalid), `mask` CV_8U.
void ReprojectNeighbour(const SoftwareRasterizer& camera_raster, const View& neighbour,
                        const cv::Mat& neighbour_image, const SoftwareRasterizer& shadow_map,
                        double occlusion_tolerance, cv::Mat* reprojected, cv::Mat* mask);

// Gaussian-weighted NCC of I and J over the pixels where mask != 0 (CV_32F result, NaN where
// undefined): with G the separable blur by `window` (GaussianWindow, zero outside the image),
// m the mask and I, J shifted by -0.5 (for float precision),
//   W = G(m), mu_I = G(mI)/W, var_I = G(mI^2)/W - mu_I^2, cov = G(mIJ)/W - mu_I mu_J, ...
//   NCC = cov / sqrt(var_I var_J), clamped to [-1, 1];
// undefined where m = 0 at the pixel itself, W < min_window_weight, or var_I <= max(
// min_texture_variance, 1e-5 G(mI^2)/W) (the second term: float round-off of a constant
// window), likewise for J. Returns the number of defined pixels.
int64_t WeightedNcc(const cv::Mat& I, const cv::Mat& J, const cv::Mat& mask, const cv::Mat& window,
                    double min_texture_variance, double min_window_weight, cv::Mat* ncc);

}  // namespace ms
