// What the photometric-gradient kernels (photometric_gradient.h) share, so that they sample the
// same pixels the same way: the near plane of a rendering, a pixel's ray, where a point falls in
// the neighbour's image, the neighbour's projection rate and bilinear sample with its
// derivatives, and a pixel's barycentric weights.
#pragma once

#include <algorithm>
#include <array>
#include <opencv2/core/mat.hpp>
#include <optional>

#include "mesh/mesh.h"
#include "scene/camera.h"

namespace ms {

// Near clipping plane of a rendering from `view`: 1e-3 of the median camera z of the vertices
// in front of it, so faces behind the camera are clipped and nothing in front is.
double RefineNearPlane(const Mesh& mesh, const View& view);

// The unit world ray through the centre of pixel (col, row) of a pinhole view.
class PixelRays {
 public:
  explicit PixelRays(const View& view) : rt_(view.R.transpose()), k_(view.intrinsics) {}
  Eigen::Vector3d operator()(int col, int row) const {
    return (rt_ * Eigen::Vector3d((col + 0.5 - k_.cx) / k_.fx, (row + 0.5 - k_.cy) / k_.fy, 1))
        .normalized();
  }

 private:
  Eigen::Matrix3d rt_;
  Intrinsics k_;
};

// How far the neighbour's pixel moves per unit of depth along a ray: d(u, v)/dd for the point y
// (the neighbour's camera coordinates) moving along ray_j (the ray in those coordinates).
inline Eigen::Vector2d ProjectionRate(const Intrinsics& kj, const Eigen::Vector3d& y,
                                      const Eigen::Vector3d& ray_j) {
  const double z2 = y.z() * y.z();
  return {kj.fx * (ray_j.x() * y.z() - y.x() * ray_j.z()) / z2,
          kj.fy * (ray_j.y() * y.z() - y.y() * ray_j.z()) / z2};
}

// Where the point y (the neighbour's camera coordinates) falls in the neighbour's image: the
// array coordinates of its bilinear sample and the pixel that holds it. Nothing when y is not
// beyond the near plane `near_j` or its sample leaves the image.
struct NeighbourPixel {
  double ax, ay;  // array coordinates of the sample
  int col, row;
};
inline std::optional<NeighbourPixel> ProjectToNeighbour(const Intrinsics& kj,
                                                        const Eigen::Vector3d& y, double near_j) {
  if (y.z() <= near_j) return std::nullopt;
  const double u = kj.fx * y.x() / y.z() + kj.cx, v = kj.fy * y.y() / y.z() + kj.cy;
  const double ax = u - 0.5, ay = v - 0.5;
  if (!(ax >= 0 && ay >= 0 && ax <= kj.width - 1 && ay <= kj.height - 1)) return std::nullopt;
  return NeighbourPixel{ax, ay, std::min(static_cast<int>(u), kj.width - 1),
                        std::min(static_cast<int>(v), kj.height - 1)};
}

// Bilinear sample of `image` (CV_64F) at array coordinates (x, y) with its exact derivatives.
// The caller keeps (x, y) within [0, cols - 1] x [0, rows - 1].
struct BilinearSample {
  double value, dx, dy;
};
inline BilinearSample SampleBilinear(const cv::Mat& image, double x, double y) {
  const int x0 = std::min(static_cast<int>(x), image.cols - 2);
  const int y0 = std::min(static_cast<int>(y), image.rows - 2);
  const double fx = x - x0, fy = y - y0;
  const double* r0 = image.ptr<double>(y0) + x0;
  const double* r1 = image.ptr<double>(y0 + 1) + x0;
  const double i00 = r0[0], i10 = r0[1], i01 = r1[0], i11 = r1[1];
  return {(1 - fy) * ((1 - fx) * i00 + fx * i10) + fy * ((1 - fx) * i01 + fx * i11),
          (1 - fy) * (i10 - i00) + fy * (i11 - i01), (1 - fx) * (i01 - i00) + fx * (i11 - i10)};
}

// The barycentric weights (phi0, phi1, 1 - phi0 - phi1) of a pixel's point, clamped to its face
// and renormalised: a rasteriser gives an edge pixel to a face by its own rounding, and the
// pixel's point may lie a rounding error outside it; a negative weight could make a vertex's
// summed weight and parallax rate negative, which the coordinator refuses from a worker.
inline std::array<double, 3> BarycentricOnFace(double phi0, double phi1) {
  const double a = std::max(phi0, 0.0), b = std::max(phi1, 0.0);
  const double c = std::max(1 - phi0 - phi1, 0.0);
  const double sum = a + b + c;  // at least 1
  return {a / sum, b / sum, c / sum};
}

}  // namespace ms
