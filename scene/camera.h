// Calibrated camera: intrinsics (pinhole + radial/tangential distortion) and pose.
//
// Conventions (docs/reference/conventions.md):
// - Image coordinates put the top-left corner of the image at (0,0), so the centre of pixel
//   (col,row) is (col+0.5, row+0.5) (COLMAP's convention, and OpenGL's window coordinates).
//   Principal points are taken from each format as given.
// - Pose: x_cam = R * X_world + t; the camera looks down +z, x right, y down.
// - Distortion follows OpenCV's model on normalised coordinates (k1,k2,p1,p2,k3).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace ms {

struct Intrinsics {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0;  // focal lengths in pixels
  double cx = 0, cy = 0;  // principal point in pixels (corner-origin convention)
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;  // OpenCV distortion, 0 = none

  bool HasDistortion() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0 || k3 != 0; }
  Eigen::Matrix3d K() const;
  // Distorts normalised coordinates (x/z, y/z) with the model above.
  Eigen::Vector2d Distort(const Eigen::Vector2d& normalized) const;
  // Inverts Distort by fixed-point iteration (converges for realistic lenses).
  Eigen::Vector2d Undistort(const Eigen::Vector2d& distorted_normalized) const;
  bool operator==(const Intrinsics& o) const;
};

struct View {
  std::string name;        // image name as the source format wrote it (often relative)
  std::string image_path;  // resolved path of the image file; empty if unknown
  Intrinsics intrinsics;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // world -> camera
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d Center() const { return -R.transpose() * t; }
  // Unit optical axis (camera +z) in world coordinates.
  Eigen::Vector3d Axis() const { return R.row(2).transpose(); }
  Eigen::Vector3d ToCamera(const Eigen::Vector3d& X) const { return R * X + t; }
  // Pinhole projection with distortion applied. Returns false if X is behind the camera.
  bool Project(const Eigen::Vector3d& X, Eigen::Vector2d* pixel) const;
  // Unit world-space ray through a pixel (distortion removed).
  Eigen::Vector3d PixelRay(const Eigen::Vector2d& pixel) const;
  // 3x4 projection matrix K [R | t] (ignores distortion).
  Eigen::Matrix<double, 3, 4> ProjectionMatrix() const;
  void SetCenter(const Eigen::Vector3d& center) { t = -R * center; }
};

// Quaternion (w, x, y, z) <-> rotation matrix helpers used by several formats.
Eigen::Matrix3d RotationFromQuaternion(double w, double x, double y, double z);
Eigen::Vector4d QuaternionFromRotation(const Eigen::Matrix3d& R);  // (w, x, y, z), w >= 0

// True if R is a rotation (orthonormal, det +1) within tolerance.
bool IsRotation(const Eigen::Matrix3d& R, double tolerance = 1e-5);

}  // namespace ms
