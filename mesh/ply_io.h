// PLY behind mesh/mesh_io.h. Header + element model per the PLY spec (Greg Turk, 1994): any
// element order, any scalar type name (char .. double and int8 .. float64), list properties
// with any integer count/index type; unknown elements and properties are skipped.
#pragma once

#include <string>
#include <string_view>

#include "mesh/mesh.h"
#include "mesh/mesh_io.h"

namespace ms {

Mesh ParsePlyMesh(std::string_view data, const std::string& name);
PointCloud ParsePlyPointCloud(std::string_view data, const std::string& name);

// Whole files as bytes. Throw InternalError when the model is inconsistent (index out of range,
// colour count differs from vertex count, non-finite coordinate): that is a programming error.
std::string FormatPlyMesh(const Mesh& mesh, const MeshWriteOptions& options);
std::string FormatPlyPointCloud(const PointCloud& cloud, const MeshWriteOptions& options);

}  // namespace ms
