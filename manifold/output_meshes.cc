#include "manifold/output_meshes.h"

#include <spdlog/spdlog.h>

#include "base/check.h"
#include "base/memory.h"

namespace ms {

OutputMeshes MakeOutputMeshes(const DelaunayManifold& manifold, Mesh surface,
                              const SurfaceInfo& info, bool float_cleanup) {
  MS_CHECK(info.vertex_ids.size() == surface.vertices.size()) << "SurfaceInfo of another mesh";
  OutputMeshes out;
  out.closed = std::move(surface);
  std::vector<uint8_t> steiner = SteinerFlags(info);
  if (float_cleanup && !out.closed.faces.empty()) {
    // A cleanup that must be undone extracts the surface again: no copy is held meanwhile.
    out.cleanup = CleanForFloatingPoint(&out.closed, &steiner, {},
                                        [&manifold] { return manifold.ExtractSurface(); });
    ReleaseFreeMemory();  // the cleaner's structures, before the surface proper is made
    const FloatCleanupStats& c = out.cleanup;
    if (c.problems_before > 0) {
      spdlog::log(c.problems_after > 0 ? spdlog::level::warn : spdlog::level::info,
                  "float cleanup: {} floating-point problems (pairs within {:.3g} or crossing in "
                  "double precision) -> {}: {} edge collapses, {} splits, {} moves, {} rounds, "
                  "{:.2f} s",
                  c.problems_before, c.tolerance, c.problems_after, c.collapses, c.splits, c.moves,
                  c.rounds, c.seconds);
    }
  }
  out.surface = FacesWithoutFlaggedVertices(out.closed, steiner);
  // Written, the surface proper must be a 2-manifold with boundary (check-mesh, Open3D); the
  // sweep jobs take every face of it, bow-ties included (SurfaceWithoutSteinerFaces).
  const int64_t dropped = KeepOneFanPerVertex(&out.surface);
  if (dropped > 0) {
    spdlog::info("surface proper: {} faces dropped where a vertex kept two fans", dropped);
  }
  return out;
}

}  // namespace ms
