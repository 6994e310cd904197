// The fast kernel's rasteriser (sweep/cpu_sweep.h): the same pixels as SoftwareRasterizer (same
// clipping, edge functions and fill rule: sweep/raster_rules.h) but found a row span at a time,
// and only what the fast kernel needs per pixel: 1/z of the nearest surface (float) and, for C,
// the face id. 1/z is affine in the image, so a span is filled by a vectorisable loop.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "base/large_buffer.h"
#include "scene/camera.h"
#include "sweep/raster_rules.h"

namespace ms {

class SpanRasterizer {
 public:
  // `view` must be a pinhole view (distortion is ignored). keep_face: also record face ids.
  SpanRasterizer(const View& view, double near, bool keep_face);

  // Targets another view (the image is undefined until the next DrawSoup); the buffers are
  // kept, so a rasteriser reused view after view allocates once.
  void SetView(const View& view, double near);

  // Clears the image and draws the triangles (world coordinates) with face ids = their indices;
  // nearest wins, ties to the lower index. Triangles are set up first, then filled a band of
  // rows at a time (each band's rows fit in the cache), every band in index order: the same
  // writes per pixel, in the same order, as drawing the triangles one after the other.
  void DrawSoup(const std::vector<std::array<Eigen::Vector3d, 3>>& soup);

  int width() const { return width_; }
  int height() const { return height_; }
  // 1 / camera z of the nearest surface, 0 where nothing was drawn. Row-major.
  const LargeBuffer<float>& inverse_depth() const { return inv_z_; }
  // Face of the nearest surface, -1 where empty (keep_face only).
  const LargeBuffer<int32_t>& face() const { return face_; }

 private:
  // A triangle projected and set up for filling: its pixel bounds and 1/z = gx x + gy y + g0.
  struct Projected {
    std::array<raster::Point2, 3> p;  // positively oriented
    double g0, gx, gy;
    int col_lo, col_hi, row_lo, row_hi;
    int32_t face;
  };
  void Clear();
  // Sets up (a, b, c) in camera coordinates, appending to projected_ if any pixel may be covered.
  void Project(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
               int32_t face);
  // Fills rows [row_begin, row_end] of a set-up triangle.
  void FillRows(const Projected& t, int row_begin, int row_end);

  Eigen::Matrix3d R_;
  Eigen::Vector3d t_;
  double fx_, fy_, cx_, cy_, near_;
  int width_, height_;
  bool keep_face_;
  int band_rows_;  // rows per band: about 256 KiB of image
  LargeBuffer<float> inv_z_;
  LargeBuffer<int32_t> face_;
  std::vector<Projected> projected_;
  std::vector<uint32_t> band_start_, band_triangles_;  // per band, its triangles (CSR)
};

}  // namespace ms
