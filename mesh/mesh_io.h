// Mesh and point files: PLY (binary little-endian or ASCII; big-endian read too) and OBJ.
// Files open in MeshLab and Open3D. Writes are atomic (temporary name, then rename).
#pragma once

#include <string>

#include "mesh/mesh.h"

namespace ms {

struct MeshWriteOptions {
  bool binary = true;  // PLY: binary_little_endian (default) or ascii
};

// Reads .ply or .obj by extension. Faces with more than 3 corners are fan-triangulated.
// Throws InputError naming file and element/line on malformed input.
Mesh ReadMesh(const std::string& path);
void WriteMesh(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options = {});

// Point clouds as PLY vertex-only files (x y z [nx ny nz] [red green blue] [quality]).
PointCloud ReadPointCloud(const std::string& path);
void WritePointCloud(const PointCloud& cloud, const std::string& path,
                     const MeshWriteOptions& options = {});

}  // namespace ms
