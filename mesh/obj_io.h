// Wavefront OBJ behind mesh/mesh_io.h: `v x y z [w] [r g b]` and `f` with v, v/vt, v//vn and
// v/vt/vn corners, negative (relative) indices and polygons; other statements are ignored.
#pragma once

#include <string>
#include <string_view>

#include "mesh/mesh.h"

namespace ms {

Mesh ParseObjMesh(std::string_view data, const std::string& name);
// Whole file as text (`v x y z [r g b]`, `f a b c`, 1-based). InternalError on an inconsistent
// mesh, as FormatPlyMesh.
std::string FormatObjMesh(const Mesh& mesh);

}  // namespace ms
