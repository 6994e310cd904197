// The fast kernel's rasteriser (sweep/cpu_sweep.h): the same pixels as SoftwareRasterizer (same
// clipping, edge functions and fill rule: sweep/raster_rules.h) but found a row span at a time,
// and only what the fast kernel needs per pixel: 1/z of the nearest surface (float) and, for C,
// the face id. 1/z is affine in the image, so a span is filled by a vectorisable loop.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "scene/camera.h"

namespace ms {

class SpanRasterizer {
 public:
  // `view` must be a pinhole view (distortion is ignored). keep_face: also record face ids.
  SpanRasterizer(const View& view, double near, bool keep_face);

  void Clear();
  // Draws the triangle (a, b, c) given in world coordinates; nearest wins, ties to the first.
  void DrawTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    int32_t face);

  int width() const { return width_; }
  int height() const { return height_; }
  // 1 / camera z of the nearest surface, 0 where nothing was drawn. Row-major.
  const std::vector<float>& inverse_depth() const { return inv_z_; }
  // Face of the nearest surface, -1 where empty (keep_face only).
  const std::vector<int32_t>& face() const { return face_; }

 private:
  void DrawProjected(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     int32_t face);

  Eigen::Matrix3d R_;
  Eigen::Vector3d t_;
  double fx_, fy_, cx_, cy_, near_;
  int width_, height_;
  bool keep_face_;
  std::vector<float> inv_z_;
  std::vector<int32_t> face_;
};

}  // namespace ms
