// The visibility counts of a tile's cells (docs/design/scalability.md, "Tiles"): the viewing
// rays a tile walks and what it counts on a cell (TileManifold counts them, tile_manifold.h). A
// tile holds only the points its stars need, so most of its viewing rays end at points it does
// not hold; it walks each ray that may reach its cells through its own triangulation, to the
// ray's end point wherever that lies. A cell whose four points are a cell of the whole
// triangulation is crossed by the same rays in any triangulation that holds it, so its counts
// are the whole triangulation's exactly.
#pragma once

#include <array>
#include <cstdint>

namespace ms {

// A viewing ray: from camera `camera`'s centre to point `point` (ids into the caller's arrays).
struct ViewingRay {
  int32_t camera = 0;
  int32_t point = 0;
};

struct CellRayCount {
  std::array<int32_t, 4> ids{};  // the cell's point ids, ascending
  int64_t crossings = 0;         // rays whose open segment meets the open cell
  // Of those, the rays that spread w2 across the face opposite ids[i] (CellLabels::Spread:
  // under the paper's rule those whose camera is beyond that face).
  std::array<int64_t, 4> spread{};

  bool operator==(const CellRayCount& o) const {
    return ids == o.ids && crossings == o.crossings && spread == o.spread;
  }
};

struct CellRayCountStats {
  int64_t rays = 0;         // rays given
  int64_t rays_walked = 0;  // of those, rays whose segment meets the counted cells' bounding box
  int64_t cell_steps = 0;   // cells the walks stepped through
  double seconds = 0;       // walking
};

}  // namespace ms
