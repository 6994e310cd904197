// The meshes a run writes, from the manifold's surface: the closed 2-manifold, made robust in
// floating point (mesh/float_cleanup.h) unless --manifold.float-cleanup is off, and the surface
// proper (its faces with no Steiner vertex, where a vertex kept two fans only the larger: a
// 2-manifold with boundary).
#pragma once

#include <functional>

#include "manifold/delaunay_manifold.h"
#include "mesh/float_cleanup.h"
#include "mesh/mesh.h"

namespace ms {

struct OutputMeshes {
  Mesh closed;
  Mesh surface;               // the faces of `closed` with no Steiner vertex, one fan per vertex
  FloatCleanupStats cleanup;  // all zero when not cleaned
};

// `surface` and `info` from DelaunayManifold::ExtractSurface; `extract_again` makes `surface`
// again, for a cleanup that must be undone (so that no copy of it is held meanwhile).
OutputMeshes MakeOutputMeshes(Mesh surface, const SurfaceInfo& info, bool float_cleanup,
                              const std::function<Mesh()>& extract_again);

}  // namespace ms
