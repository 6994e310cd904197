// A small software rasterizer with the rules the GLSL sweep must follow (docs/design/sweep.md), so
// the two can be compared pixel by pixel:
// - pinhole projection u = fx x/z + cx, v = fy y/z + cy; pixel (col, row) is sampled at its
//   centre (col + 0.5, row + 0.5) (corner-origin convention, docs/reference/conventions.md);
// - triangles are clipped against the near plane z = near in camera space, never culled;
// - coverage by edge functions with the top-left fill rule (in y-down image coordinates), so
//   triangles sharing an edge never both cover a pixel and leave no gap;
// - perspective-correct interpolation (barycentrics weighted by 1/z), depth = camera z;
// - depth test "less": the first triangle drawn wins ties.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "scene/camera.h"

namespace ms {

class SoftwareRasterizer {
 public:
  // `view` must be a pinhole view (distortion is ignored). With keep_world false only depth is
  // kept (a shadow map); otherwise also the world position and face id of every covered pixel.
  SoftwareRasterizer(const View& view, double near, bool keep_world);

  void Clear();
  // Draws the triangle (a, b, c) given in world coordinates.
  void DrawTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    int32_t face);

  int width() const { return width_; }
  int height() const { return height_; }
  // Camera z of the nearest surface, +infinity where nothing was drawn. Row-major.
  const std::vector<double>& depth() const { return depth_; }
  // World position / face of the nearest surface (keep_world only); face -1 where empty.
  const std::vector<Eigen::Vector3d>& world() const { return world_; }
  const std::vector<int32_t>& face() const { return face_; }
  bool Covered(int col, int row) const {
    return face_.empty() ? depth_[Index(col, row)] < kEmpty : face_[Index(col, row)] >= 0;
  }
  size_t Index(int col, int row) const { return static_cast<size_t>(row) * width_ + col; }

  static constexpr double kEmpty = std::numeric_limits<double>::infinity();

 private:
  struct ClipVertex {
    Eigen::Vector3d camera;  // camera coordinates
    Eigen::Vector3d world;
  };
  void DrawClipped(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c, int32_t face);

  Eigen::Matrix3d R_;
  Eigen::Vector3d t_;
  double fx_, fy_, cx_, cy_, near_;
  int width_, height_;
  bool keep_world_;
  std::vector<double> depth_;
  std::vector<Eigen::Vector3d> world_;
  std::vector<int32_t> face_;
};

}  // namespace ms
