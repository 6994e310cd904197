// The visibility counts of some cells of a triangulation of some of the scene's points: what a
// tile coordinator counts on the cells it owns (docs/design/scalability.md, "Tiles"). A tile
// holds only the points its stars need, so most of its viewing rays end at points it does not
// hold; it walks each ray that may reach its cells through its own triangulation, to the ray's
// end point wherever that lies, and counts the crossings of the cells it was asked for. A cell
// whose four points are a cell of the whole triangulation is crossed by the same rays in any
// triangulation that holds it, so those counts are the whole triangulation's exactly.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace ms {

// A viewing ray: from camera `camera`'s centre to point `point` (ids into the caller's arrays).
struct ViewingRay {
  int32_t camera = 0;
  int32_t point = 0;
};

struct CellRayCount {
  std::array<int32_t, 4> ids{};  // the cell's point ids, ascending
  int64_t crossings = 0;         // rays whose open segment meets the open cell
  // Of those, the rays whose camera is beyond the face opposite ids[i] (they spread w2 across
  // it under the paper's rule, CellLabels::CountCrossing).
  std::array<int64_t, 4> camera_beyond{};
};

struct CellRayCountStats {
  int64_t rays = 0;         // rays given
  int64_t rays_walked = 0;  // of those, rays whose segment meets the counted cells' bounding box
  int64_t cell_steps = 0;   // cells the walks stepped through
  double seconds = 0;       // triangulating, locating the cameras and walking
};

// Triangulates points[held] (pairwise distinct; their convex hull must hold every camera and
// every ray's end point) and returns the counts of the finite cells for which counted(ids)
// holds, ids ascending, sorted by ids. Throws InputError for an id out of range, a repeated
// point, or a camera or ray end outside the hull.
std::vector<CellRayCount> CountRaysOnCells(
    const std::vector<Eigen::Vector3d>& points, const std::vector<int32_t>& held,
    const std::vector<Eigen::Vector3d>& camera_centres, const std::vector<ViewingRay>& rays,
    const std::function<bool(const std::array<int32_t, 4>&)>& counted,
    CellRayCountStats* stats = nullptr);

}  // namespace ms
