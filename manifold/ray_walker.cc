#include "manifold/ray_walker.h"

namespace ms::manifold_detail {

void RayWalker::LocateCameras(const std::vector<Eigen::Vector3d>& centers) {
  MS_CHECK(centers.size() == camera_cells_.size()) << "camera count changed";
  camera_points_.clear();
  for (const Eigen::Vector3d& c : centers) camera_points_.push_back(ToPoint(c));
  for (size_t c = 0; c < centers.size(); ++c) {
    camera_cells_[c].valid = false;
    StartOf(static_cast<int>(c));
  }
}

const CameraStart& RayWalker::StartOf(int camera) {
  CameraStart& start = camera_cells_[camera];
  if (!start.valid) {
    start.cell = dt_.locate(camera_points_[camera], start.type, start.li, start.lj);
    start.valid = true;
    start.cell->info().has_camera = true;
  }
  return start;
}

void RayWalker::LocateStarts() {
  if (starts_located_) return;
  for (size_t c = 0; c < camera_cells_.size(); ++c) StartOf(static_cast<int>(c));
  starts_located_ = true;
}

CameraStart RayWalker::Locate(int camera) const {
  CameraStart start;
  start.cell = dt_.locate(camera_points_[camera], start.type, start.li, start.lj);
  start.valid = true;
  return start;
}

void RayWalker::ForgetStartsIn(const Cell_handle& c) {
  for (CameraStart& start : camera_cells_) {
    if (start.valid && start.cell == c) {
      start.valid = false;
      starts_located_ = false;
    }
  }
}

uint32_t RayWalker::NextStamp() {
  if (++stamp_ == 0) {
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) c->info().stamp = 0;
    stamp_ = 1;
  }
  return stamp_;
}

std::vector<Cell_handle> RayWalker::StartCandidates(const CameraStart& start,
                                                    bool concurrent) const {
  std::vector<Cell_handle> cells;
  switch (start.type) {
    case Delaunay::CELL:
      cells.push_back(start.cell);
      break;
    case Delaunay::FACET:
      cells.push_back(start.cell);
      cells.push_back(start.cell->neighbor(start.li));
      break;
    case Delaunay::EDGE: {
      auto circ = dt_.incident_cells(start.cell, start.li, start.lj), done = circ;
      do {
        cells.push_back(circ);
      } while (++circ != done);
      break;
    }
    case Delaunay::VERTEX:
      IncidentCells(start.cell->vertex(start.li), concurrent, &cells);
      break;
    default:
      MS_CHECK(false) << "camera outside the triangulation (locate type " << start.type << ")";
  }
  return cells;
}

}  // namespace ms::manifold_detail
