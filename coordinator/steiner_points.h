// Steiner points: a coarse grid on the faces of an enlarged bounding box.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace ms {

// Points on the surface of the box [min, max] enlarged by margin * diagonal on every side,
// `grid` points per box edge (corners included). Each point is jittered deterministically by a
// few percent of the grid spacing along the face, so no five are cospherical and no four
// coplanar with each other.
std::vector<Eigen::Vector3d> MakeSteinerPoints(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                                               double margin, int grid);

}  // namespace ms
