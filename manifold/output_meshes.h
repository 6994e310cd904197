// The meshes a run writes, from the manifold's surface: the closed 2-manifold, made robust in
// floating point (mesh/float_cleanup.h) unless --manifold.float-cleanup is off, and the surface
// proper (its faces with no Steiner vertex, where a vertex kept two fans only the larger: a
// 2-manifold with boundary).
#pragma once

#include "manifold/delaunay_manifold.h"
#include "mesh/float_cleanup.h"
#include "mesh/mesh.h"

namespace ms {

struct OutputMeshes {
  Mesh closed;
  Mesh surface;               // the faces of `closed` with no Steiner vertex, one fan per vertex
  FloatCleanupStats cleanup;  // all zero when not cleaned
};

// `surface` and `info` from manifold.ExtractSurface, the manifold unchanged since (a cleanup
// that must be undone extracts the surface again rather than holding a copy of it).
OutputMeshes MakeOutputMeshes(const DelaunayManifold& manifold, Mesh surface,
                              const SurfaceInfo& info, bool float_cleanup);

}  // namespace ms
