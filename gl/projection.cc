#include "gl/projection.h"

#include "base/check.h"

namespace ms::gl {

Eigen::Matrix4d GlProjection(const Intrinsics& k, double near, double far, DepthRange range) {
  MS_CHECK(k.width > 0 && k.height > 0 && k.fx > 0 && k.fy > 0)
      << "bad intrinsics " << k.width << "x" << k.height << " f " << k.fx << "," << k.fy;
  MS_CHECK(near > 0 && far > near) << "bad depth range " << near << ".." << far;
  const double w = k.width, h = k.height;
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  // x_ndc = 2 (fx x/z + cx) / W - 1, y_ndc = 2 (fy y/z + cy) / H - 1 (no flip: see header).
  p(0, 0) = 2 * k.fx / w;
  p(0, 2) = 2 * k.cx / w - 1;
  p(1, 1) = 2 * k.fy / h;
  p(1, 2) = 2 * k.cy / h - 1;
  p(3, 2) = 1;  // w_clip = z
  if (range == DepthRange::kNegativeOneToOne) {
    // z_ndc = (f+n)/(f-n) - 2fn/((f-n) z): -1 at near, +1 at far.
    p(2, 2) = (far + near) / (far - near);
    p(2, 3) = -2 * far * near / (far - near);
  } else {
    // z_ndc = -n/(f-n) + fn/((f-n) z): 1 at near, 0 at far.
    p(2, 2) = -near / (far - near);
    p(2, 3) = far * near / (far - near);
  }
  return p;
}

Eigen::Matrix4d ModelView(const View& view, const Eigen::Vector3d& origin) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = view.R;
  m.topRightCorner<3, 1>() = view.R * origin + view.t;
  return m;
}

Eigen::Vector2d WindowFromCamera(const Eigen::Matrix4d& projection, const Intrinsics& k,
                                 const Eigen::Vector3d& x_cam) {
  const Eigen::Vector4d clip = projection * x_cam.homogeneous();
  const Eigen::Vector2d ndc = clip.head<2>() / clip.w();
  return {(ndc.x() + 1) * 0.5 * k.width, (ndc.y() + 1) * 0.5 * k.height};
}

}  // namespace ms::gl
