// TEMPORARY — DELETE AT MERGE. A minimal ASCII-PLY stand-in for mesh/mesh_io.h, which another
// developer implements concurrently in mesh/mesh_io.cc; it only exists so that this branch links
// and `manisweep synth/evaluate` can be tried. It writes ASCII PLY whatever the options say,
// reads ASCII PLY with x y z vertex properties (others skipped) and triangle/polygon faces, and
// rejects everything else (binary PLY, OBJ) with an InputError.
#include <fmt/format.h>

#include <string>
#include <vector>

#include "base/error.h"
#include "base/file_util.h"
#include "base/text_reader.h"
#include "mesh/mesh_io.h"

namespace ms {
namespace {

struct PlyHeader {
  int64_t vertices = 0, faces = 0;
  std::vector<std::string> vertex_properties;
};

PlyHeader ReadHeader(TextReader& reader) {
  std::string_view line = reader.RequireDataLine("'ply'", 0);
  if (Trim(line) != "ply") reader.Fail("not a PLY file (first line is not 'ply')");
  PlyHeader header;
  std::string element;
  bool ascii = false;
  while (true) {
    line = Trim(reader.RequireDataLine("end_header", 0));
    const std::vector<std::string_view> f = SplitFields(line);
    if (f.empty() || f[0] == "comment" || f[0] == "obj_info") continue;
    if (f[0] == "end_header") break;
    if (f[0] == "format") {
      ascii = f.size() >= 2 && f[1] == "ascii";
      if (!ascii) reader.Fail("only ASCII PLY is supported by this temporary reader");
    } else if (f[0] == "element" && f.size() == 3) {
      element = std::string(f[1]);
      const int64_t count = reader.ParseInt(f[2], "element count", 0, int64_t{1} << 31);
      if (element == "vertex") header.vertices = count;
      if (element == "face") header.faces = count;
    } else if (f[0] == "property" && element == "vertex" && f.size() == 3) {
      header.vertex_properties.emplace_back(f[2]);
    }
  }
  if (!ascii) reader.Fail("missing 'format ascii 1.0'");
  return header;
}

Mesh ReadPly(const std::string& path, bool faces_required) {
  TextReader reader(path);
  const PlyHeader header = ReadHeader(reader);
  int ix = -1, iy = -1, iz = -1;
  for (size_t i = 0; i < header.vertex_properties.size(); ++i) {
    if (header.vertex_properties[i] == "x") ix = static_cast<int>(i);
    if (header.vertex_properties[i] == "y") iy = static_cast<int>(i);
    if (header.vertex_properties[i] == "z") iz = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0) reader.Fail("vertex element lacks x, y or z");
  Mesh mesh;
  for (int64_t v = 0; v < header.vertices; ++v) {
    const std::vector<std::string_view> f = SplitFields(reader.RequireDataLine("a vertex", 0));
    if (f.size() < header.vertex_properties.size()) reader.Fail("vertex: too few values");
    mesh.vertices.emplace_back(reader.ParseDouble(f[ix], "x"), reader.ParseDouble(f[iy], "y"),
                               reader.ParseDouble(f[iz], "z"));
  }
  if (faces_required && header.faces == 0) reader.Fail("no faces");
  for (int64_t i = 0; i < header.faces; ++i) {
    const std::vector<std::string_view> f = SplitFields(reader.RequireDataLine("a face", 0));
    if (f.empty()) reader.Fail("empty face line");
    const int64_t n = reader.ParseInt(f[0], "face vertex count", 3, 1000);
    if (static_cast<int64_t>(f.size()) < n + 1) reader.Fail("face: too few indices");
    std::vector<int32_t> corners;
    for (int64_t k = 0; k < n; ++k) {
      corners.push_back(static_cast<int32_t>(reader.ParseInt(
          f[k + 1], "vertex index", 0, static_cast<int64_t>(mesh.vertices.size()) - 1)));
    }
    for (int64_t k = 1; k + 1 < n; ++k)
      mesh.faces.push_back({corners[0], corners[k], corners[k + 1]});
  }
  return mesh;
}

}  // namespace

Mesh ReadMesh(const std::string& path) {
  if (path.size() < 4 || path.substr(path.size() - 4) != ".ply") {
    throw InputError(path + ": only .ply meshes are readable in this build (temporary reader)");
  }
  return ReadPly(path, true);
}

void WriteMesh(const Mesh& mesh, const std::string& path, const MeshWriteOptions&) {
  WriteFileAtomically(
      path,
      [&](std::ostream& out) {
        out << "ply\nformat ascii 1.0\ncomment manisweep (temporary ASCII writer)\n";
        out << "element vertex " << mesh.vertices.size()
            << "\nproperty double x\nproperty double y\n"
            << "property double z\n";
        if (mesh.HasColors())
          out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        out << "element face " << mesh.faces.size() << "\nproperty list uchar int vertex_indices\n"
            << "end_header\n";
        for (size_t i = 0; i < mesh.vertices.size(); ++i) {
          const Eigen::Vector3d& v = mesh.vertices[i];
          out << fmt::format("{:.17g} {:.17g} {:.17g}", v.x(), v.y(), v.z());
          if (mesh.HasColors()) {
            const auto& c = mesh.vertex_colors[i];
            out << ' ' << int{c[0]} << ' ' << int{c[1]} << ' ' << int{c[2]};
          }
          out << '\n';
        }
        for (const auto& f : mesh.faces) out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
      },
      /*binary=*/false);
}

PointCloud ReadPointCloud(const std::string& path) {
  PointCloud cloud;
  cloud.points = ReadPly(path, false).vertices;
  return cloud;
}

void WritePointCloud(const PointCloud& cloud, const std::string& path, const MeshWriteOptions&) {
  const bool colors = cloud.colors.size() == cloud.points.size() && !cloud.points.empty();
  WriteFileAtomically(
      path,
      [&](std::ostream& out) {
        out << "ply\nformat ascii 1.0\ncomment manisweep (temporary ASCII writer)\n";
        out << "element vertex " << cloud.points.size()
            << "\nproperty double x\nproperty double y\nproperty double z\n";
        if (colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        out << "end_header\n";
        for (size_t i = 0; i < cloud.points.size(); ++i) {
          const Eigen::Vector3d& p = cloud.points[i];
          out << fmt::format("{:.17g} {:.17g} {:.17g}", p.x(), p.y(), p.z());
          if (colors) {
            out << ' ' << int{cloud.colors[i][0]} << ' ' << int{cloud.colors[i][1]} << ' '
                << int{cloud.colors[i][2]};
          }
          out << '\n';
        }
      },
      /*binary=*/false);
}

}  // namespace ms
