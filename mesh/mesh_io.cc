#include "mesh/mesh_io.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "mesh/obj_io.h"
#include "mesh/ply_io.h"

namespace ms {
namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

void RequirePly(const std::string& path, const char* what) {
  if (LowerExtension(path) != ".ply") {
    throw InputError(path + ": " + what + " must be a .ply file");
  }
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  WriteFileAtomically(path, [&](std::ostream& os) {
    os.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  });
}

}  // namespace

MeshFormat MeshFormatFromPath(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".ply") return MeshFormat::kPly;
  if (ext == ".obj") return MeshFormat::kObj;
  throw InputError(path + ": unknown mesh file extension '" + ext + "' (use .ply or .obj)");
}

Mesh ParseMesh(std::string_view data, MeshFormat format, const std::string& name) {
  switch (format) {
    case MeshFormat::kPly:
      return ParsePlyMesh(data, name);
    case MeshFormat::kObj:
      return ParseObjMesh(data, name);
  }
  throw InternalError("ParseMesh: unknown format");
}

Mesh ReadMesh(const std::string& path) {
  const MeshFormat format = MeshFormatFromPath(path);
  const Timer timer;
  const std::string data = ReadFileToString(path);
  Mesh mesh = ParseMesh(data, format, path);
  spdlog::debug("read {}: {} vertices, {} triangles in {:.3f} s", path, mesh.NumVertices(),
                mesh.NumFaces(), timer.Seconds());
  return mesh;
}

void WriteMesh(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options) {
  const MeshFormat format = MeshFormatFromPath(path);
  WriteBytes(path, format == MeshFormat::kPly ? FormatPlyMesh(mesh, options) : FormatObjMesh(mesh));
  spdlog::debug("wrote {}: {} vertices, {} triangles", path, mesh.NumVertices(), mesh.NumFaces());
}

PointCloud ParsePointCloud(std::string_view data, const std::string& name) {
  return ParsePlyPointCloud(data, name);
}

PointCloud ReadPointCloud(const std::string& path) {
  RequirePly(path, "a point cloud");
  return ParsePointCloud(ReadFileToString(path), path);
}

void WritePointCloud(const PointCloud& cloud, const std::string& path,
                     const MeshWriteOptions& options) {
  RequirePly(path, "a point cloud");
  WriteBytes(path, FormatPlyPointCloud(cloud, options));
}

}  // namespace ms
