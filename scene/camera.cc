#include "scene/camera.h"

#include <cmath>

namespace ms {

Eigen::Matrix3d Intrinsics::K() const {
  Eigen::Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

Eigen::Vector2d Intrinsics::Distort(const Eigen::Vector2d& n) const {
  if (!HasDistortion()) return n;
  const double x = n.x(), y = n.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

Eigen::Vector2d Intrinsics::Undistort(const Eigen::Vector2d& d) const {
  if (!HasDistortion()) return d;
  // Fixed-point iteration x <- d - (Distort(x) - x); 20 rounds reach 1e-12 for usual lenses.
  Eigen::Vector2d x = d;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector2d next = x - (Distort(x) - d);
    if ((next - x).squaredNorm() < 1e-24) return next;
    x = next;
  }
  return x;
}

bool Intrinsics::operator==(const Intrinsics& o) const {
  return width == o.width && height == o.height && fx == o.fx && fy == o.fy && cx == o.cx &&
         cy == o.cy && k1 == o.k1 && k2 == o.k2 && p1 == o.p1 && p2 == o.p2 && k3 == o.k3;
}

bool View::Project(const Eigen::Vector3d& X, Eigen::Vector2d* pixel) const {
  const Eigen::Vector3d c = ToCamera(X);
  if (!(c.z() > 0)) return false;
  const Eigen::Vector2d d = intrinsics.Distort(c.head<2>() / c.z());
  *pixel = {intrinsics.fx * d.x() + intrinsics.cx, intrinsics.fy * d.y() + intrinsics.cy};
  return true;
}

Eigen::Vector3d View::PixelRay(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d d((pixel.x() - intrinsics.cx) / intrinsics.fx,
                          (pixel.y() - intrinsics.cy) / intrinsics.fy);
  const Eigen::Vector2d n = intrinsics.Undistort(d);
  return (R.transpose() * Eigen::Vector3d(n.x(), n.y(), 1)).normalized();
}

Eigen::Matrix<double, 3, 4> View::ProjectionMatrix() const {
  Eigen::Matrix<double, 3, 4> Rt;
  Rt.leftCols<3>() = R;
  Rt.col(3) = t;
  return intrinsics.K() * Rt;
}

Eigen::Matrix3d RotationFromQuaternion(double w, double x, double y, double z) {
  return Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
}

Eigen::Vector4d QuaternionFromRotation(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;
  return {q.w(), q.x(), q.y(), q.z()};
}

bool IsRotation(const Eigen::Matrix3d& R, double tolerance) {
  if (!R.allFinite()) return false;
  const double orthogonality = (R * R.transpose() - Eigen::Matrix3d::Identity()).norm();
  return orthogonality < tolerance && std::abs(R.determinant() - 1) < tolerance;
}

}  // namespace ms
