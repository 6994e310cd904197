#include "tools/render.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "gl/mesh_renderer.h"

namespace ms {

void ShadedRenderOptions::Check() const {
  if (max_size < 0) throw InputError("render option max_size: must be >= 0");
}

View ScaledView(const View& view, int max_size) {
  const Intrinsics& k = view.intrinsics;
  const int longest = std::max(k.width, k.height);
  if (max_size <= 0 || longest <= max_size) return view;
  const double s = static_cast<double>(max_size) / longest;
  View scaled = view;
  Intrinsics& out = scaled.intrinsics;
  out.width = std::max(1, static_cast<int>(std::lround(k.width * s)));
  out.height = std::max(1, static_cast<int>(std::lround(k.height * s)));
  // Corner-origin pixel coordinates scale exactly with the image.
  const double sx = static_cast<double>(out.width) / k.width;
  const double sy = static_cast<double>(out.height) / k.height;
  out.fx = k.fx * sx;
  out.cx = k.cx * sx;
  out.fy = k.fy * sy;
  out.cy = k.cy * sy;
  return scaled;
}

cv::Mat RenderShaded(const gl::GlContext& context, const Mesh& mesh, const View& full_view,
                     const ShadedRenderOptions& options) {
  options.Check();
  const View view = ScaledView(full_view, options.max_size);
  const int width = view.intrinsics.width, height = view.intrinsics.height;
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(40, 34, 30));
  if (mesh.faces.empty()) return image;
  gl::MeshRenderer renderer(context, mesh);
  gl::DepthRenderOptions render_options;
  render_options.world_positions = false;
  const gl::DepthMaps maps = renderer.Render(view, render_options);
  std::vector<Eigen::Vector3d> normals(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) normals[f] = mesh.FaceNormal(f);
  for (int row = 0; row < height; ++row) {
    const int32_t* faces = maps.face_id.ptr<int32_t>(row);
    cv::Vec3b* out = image.ptr<cv::Vec3b>(row);
    for (int col = 0; col < width; ++col) {
      const int32_t f = faces[col];
      if (f < 0) continue;
      // Headlight: light comes from the camera along the pixel's ray.
      const Eigen::Vector3d ray = view.PixelRay({col + 0.5, row + 0.5});
      const double facing = -normals[f].dot(ray);
      const double shade = 0.18 + 0.82 * std::min(1.0, std::abs(facing));
      const uint8_t v = static_cast<uint8_t>(std::lround(255 * shade));
      out[col] = facing >= 0
                     ? cv::Vec3b(v, v, v)
                     : cv::Vec3b(static_cast<uint8_t>(v / 3), static_cast<uint8_t>(v / 3), v);
    }
  }
  return image;
}

}  // namespace ms
