#include "mesh/obj_io.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include "base/error.h"
#include "base/text_reader.h"

#ifndef MS_VERSION
#define MS_VERSION "unknown"
#endif

namespace ms {
namespace {

double ParseObjReal(const TextReader& reader, std::string_view token, const char* field) {
  std::string_view digits = token;
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  double value = 0;
  const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec == std::errc::result_out_of_range && ptr == digits.data() + digits.size()) {
    value = std::strtod(std::string(digits).c_str(), nullptr);  // underflow: 0, overflow: inf
  } else if (ec != std::errc() || ptr != digits.data() + digits.size() || digits.empty()) {
    reader.Fail(std::string(field) + ": '" + std::string(token) + "' is not a number");
  }
  if (!std::isfinite(value)) {
    reader.Fail(std::string(field) + ": '" + std::string(token) + "' is not finite");
  }
  return value;
}

// The vertex part of a face corner ("7", "7/3", "7//2", "7/3/2"), resolved to 1-based.
int64_t ParseCorner(const TextReader& reader, std::string_view token, int64_t num_vertices) {
  const std::string_view head = token.substr(0, token.find('/'));
  int64_t index = 0;
  const auto [ptr, ec] = std::from_chars(head.data(), head.data() + head.size(), index);
  if (ec != std::errc() || ptr != head.data() + head.size() || head.empty()) {
    reader.Fail("face corner '" + std::string(token) + "' does not start with a vertex index");
  }
  if (index == 0)
    reader.Fail("face corner '" + std::string(token) + "': index 0 (OBJ counts from 1)");
  if (index < 0) {
    // Relative to the vertices defined so far: -1 is the last one.
    const int64_t absolute = num_vertices + index + 1;
    if (absolute < 1) {
      reader.Fail("face corner '" + std::string(token) + "': relative index reaches before the " +
                  "first vertex (" + std::to_string(num_vertices) + " defined so far)");
    }
    return absolute;
  }
  return index;
}

}  // namespace

Mesh ParseObjMesh(std::string_view data, const std::string& name) {
  TextReader reader(name, std::string(data));
  Mesh mesh;
  std::vector<std::array<double, 3>> colors;  // of the vertices that have them, as written
  size_t vertices_without_color = 0;
  // Positive indices may name vertices defined later, so the range check waits for the end;
  // remember each triangle's line for that error.
  std::vector<std::array<int64_t, 3>> triangles;
  std::vector<int> triangle_lines;
  std::vector<int64_t> polygon;
  size_t ignored_statements = 0;
  std::string_view line;
  while (reader.NextDataLine(&line, '#')) {
    line = line.substr(0, line.find('#'));  // a comment may also end a statement
    const std::vector<std::string_view> f = SplitFields(line);
    if (f.empty()) continue;
    const std::string_view key = f[0];
    if (key == "v") {
      if (f.size() != 4 && f.size() != 5 && f.size() != 7) {
        reader.Fail("vertex: expected 'v x y z [w]' or 'v x y z r g b', found " +
                    std::to_string(f.size() - 1) + " numbers");
      }
      mesh.vertices.emplace_back(ParseObjReal(reader, f[1], "vertex x"),
                                 ParseObjReal(reader, f[2], "vertex y"),
                                 ParseObjReal(reader, f[3], "vertex z"));
      if (f.size() == 5) ParseObjReal(reader, f[4], "vertex w");
      if (f.size() == 7) {
        colors.push_back({ParseObjReal(reader, f[4], "vertex red"),
                          ParseObjReal(reader, f[5], "vertex green"),
                          ParseObjReal(reader, f[6], "vertex blue")});
      } else {
        ++vertices_without_color;
      }
    } else if (key == "f" || key == "fo") {
      if (f.size() < 4) {
        reader.Fail("face: needs at least 3 corners, found " + std::to_string(f.size() - 1));
      }
      const auto num_vertices = static_cast<int64_t>(mesh.vertices.size());
      polygon.clear();
      for (size_t k = 1; k < f.size(); ++k)
        polygon.push_back(ParseCorner(reader, f[k], num_vertices));
      for (size_t k = 1; k + 1 < polygon.size(); ++k) {
        triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
        triangle_lines.push_back(reader.line_number());
      }
    } else {
      // vt, vn, vp, g, o, s, l, p, usemtl, mtllib, ...: not part of the triangle mesh.
      ++ignored_statements;
    }
  }
  if (ignored_statements > 0) {
    spdlog::debug("{}: {} statements other than v and f ignored", name, ignored_statements);
  }
  const auto num_vertices = static_cast<int64_t>(mesh.vertices.size());
  if (num_vertices > INT32_MAX) {
    throw InputError(name + ": " + std::to_string(num_vertices) +
                     " vertices are more than a mesh can index");
  }
  mesh.faces.reserve(triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    std::array<int32_t, 3> face;
    for (int k = 0; k < 3; ++k) {
      const int64_t index = triangles[t][k];
      if (index > num_vertices) {
        throw InputError(name + ":" + std::to_string(triangle_lines[t]) + ": face: vertex index " +
                         std::to_string(index) + " is out of range (the file has " +
                         std::to_string(num_vertices) + " vertices)");
      }
      face[k] = static_cast<int32_t>(index - 1);
    }
    mesh.faces.push_back(face);
  }
  if (vertices_without_color == 0 && !colors.empty()) {
    // MeshLab writes colours in [0, 1]; some tools write 0..255. Decide once per file.
    double max_value = 0;
    for (const auto& c : colors) max_value = std::max({max_value, c[0], c[1], c[2]});
    const double scale = max_value <= 1.0 ? 255.0 : 1.0;
    mesh.vertex_colors.reserve(colors.size());
    for (const auto& c : colors) {
      std::array<uint8_t, 3> byte;
      for (int k = 0; k < 3; ++k) {
        byte[k] = static_cast<uint8_t>(std::clamp(std::round(c[k] * scale), 0.0, 255.0));
      }
      mesh.vertex_colors.push_back(byte);
    }
  } else if (vertices_without_color != mesh.vertices.size()) {
    spdlog::warn("{}: only some vertices have colours; colours ignored", name);
  }
  return mesh;
}

std::string FormatObjMesh(const Mesh& mesh) {
  const size_t nv = mesh.vertices.size();
  if (mesh.HasColors() && mesh.vertex_colors.size() != nv) {
    throw InternalError("writing OBJ: " + std::to_string(mesh.vertex_colors.size()) +
                        " vertex colours for " + std::to_string(nv) + " vertices");
  }
  std::string out = fmt::format("# written by manisweep {}\n# {} vertices, {} triangles\n",
                                MS_VERSION, nv, mesh.faces.size());
  out.reserve(out.size() + nv * 64 + mesh.faces.size() * 32);
  for (size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3d& p = mesh.vertices[i];
    if (!p.allFinite()) {
      throw InternalError("writing OBJ: vertex " + std::to_string(i) + " is not finite");
    }
    fmt::format_to(std::back_inserter(out), "v {} {} {}", p.x(), p.y(), p.z());
    if (mesh.HasColors()) {
      const auto& c = mesh.vertex_colors[i];
      fmt::format_to(std::back_inserter(out), " {:.6g} {:.6g} {:.6g}", c[0] / 255.0, c[1] / 255.0,
                     c[2] / 255.0);
    }
    out += '\n';
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    for (int32_t v : face) {
      if (v < 0 || static_cast<size_t>(v) >= nv) {
        throw InternalError("writing OBJ: face " + std::to_string(f) + " has vertex index " +
                            std::to_string(v) + " out of range [0, " + std::to_string(nv) + ")");
      }
    }
    fmt::format_to(std::back_inserter(out), "f {} {} {}\n", face[0] + 1, face[1] + 1, face[2] + 1);
  }
  return out;
}

}  // namespace ms
