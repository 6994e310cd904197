// The pinhole camera (scene/camera.h) as OpenGL matrices. Pure math, no GL calls.
//
// Image convention: pixel (col,row) has its centre at (col+0.5, row+0.5), origin at the top-left
// corner. GL rasterises at window coordinates (i+0.5, j+0.5) with j counted from the bottom.
// GlProjection maps image y straight to window y (y_window = y_image), so framebuffer row r
// holds image row r: read-backs need no flip and a texture made from an image is sampled at
// v = y / height. Consequence: the picture is mirrored vertically in GL's own terms, so a face
// that is counter-clockwise seen from the camera (the project's "front",
// docs/reference/conventions.md) is clockwise in window space: cull with glFrontFace(GL_CW) +
// glCullFace(GL_BACK).
//
// Depth: the camera-space z of a fragment is affine in the triangle, so it is interpolated
// exactly (perspective-correct) and shaders write it to a float target; the hardware depth
// buffer only resolves visibility. With DepthRange::kReversedZeroToOne (glClipControl(
// GL_LOWER_LEFT, GL_ZERO_TO_ONE), clear depth to 0, glDepthFunc(GL_GREATER)) float depth keeps
// near-uniform relative precision from `near` to `far`; kNegativeOneToOne is GL's default
// (clear to 1, GL_LESS). Lens distortion is ignored: this renders the undistorted pinhole image.
#pragma once

#include <Eigen/Core>

#include "scene/camera.h"

namespace ms::gl {

enum class DepthRange { kNegativeOneToOne, kReversedZeroToOne };

// Camera coordinates (x right, y down, z forward) -> clip coordinates, for an image of
// intrinsics.width x intrinsics.height pixels. near/far: the z range kept (0 < near < far).
Eigen::Matrix4d GlProjection(const Intrinsics& intrinsics, double near, double far,
                             DepthRange range);

// World coordinates relative to `origin` -> camera coordinates: x_cam = R (X_rel + origin) + t.
// Uploading vertices relative to a nearby origin keeps float precision in large scenes.
Eigen::Matrix4d ModelView(const View& view, const Eigen::Vector3d& origin);

// Pixel position (image convention) of camera point x_cam under GlProjection, as GL computes
// it: clip -> NDC -> window. Matches View::Project for undistorted cameras; used in tests.
Eigen::Vector2d WindowFromCamera(const Eigen::Matrix4d& projection, const Intrinsics& intrinsics,
                                 const Eigen::Vector3d& x_cam);

}  // namespace ms::gl
