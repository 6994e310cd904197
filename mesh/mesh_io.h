// Mesh and point files: PLY (binary little-endian or ASCII written; ASCII, little- and big-endian
// read) and OBJ. Written files open in MeshLab and Open3D. Writes are atomic (temporary name,
// then rename). Readers are bounded: counts are checked against the file size before anything
// is allocated, indices are range-checked, non-finite coordinates are rejected, and every error
// is an InputError naming the file and the element/line/byte.
#pragma once

#include <string>
#include <string_view>

#include "mesh/mesh.h"

namespace ms {

enum class MeshFormat { kPly, kObj };

// By extension (case-insensitive): .ply or .obj. Throws InputError naming the path otherwise.
MeshFormat MeshFormatFromPath(const std::string& path);

struct MeshWriteOptions {
  bool binary = true;              // PLY: binary_little_endian (default) or ascii. OBJ: ignored.
  bool float_coordinates = false;  // PLY: x y z as float (half the size) instead of double
                                   // (exact: a checker then sees what the builder made).
};

// Reads .ply or .obj by extension. Faces with more than 3 corners are fan-triangulated
// (v0 vi vi+1). Vertex colours are kept when every vertex has them.
Mesh ReadMesh(const std::string& path);
// The same from memory (fuzzing, tests); `name` stands for the file in error messages.
Mesh ParseMesh(std::string_view data, MeshFormat format, const std::string& name);
void WriteMesh(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options = {});

// Point clouds as PLY vertex-only files (x y z [nx ny nz] [red green blue] [quality]); faces in
// the file, if any, are skipped. `scalar` is read as a synonym of `quality`.
PointCloud ReadPointCloud(const std::string& path);
PointCloud ParsePointCloud(std::string_view data, const std::string& name);
void WritePointCloud(const PointCloud& cloud, const std::string& path,
                     const MeshWriteOptions& options = {});

}  // namespace ms
