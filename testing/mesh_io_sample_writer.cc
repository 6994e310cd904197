// Test helper for tests/tools/open3d_ply_check.py: writes meshes and point clouds with our
// writers, plus expected.json holding what they contain, so that another library (Open3D) can
// read the files and compare. Usage: mesh_io_sample_writer OUTPUT_DIR
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "mesh/mesh_io.h"

namespace {

// A torus with irregular coordinates (not exactly representable as floats) and colours.
ms::Mesh SampleMesh() {
  ms::Mesh m;
  const int n = 16, k = 9;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / k;
      m.vertices.emplace_back((3.1 + std::cos(v)) * std::cos(u) + 1.0 / 3.0,
                              (3.1 + std::cos(v)) * std::sin(u) - 1e3, std::sin(v) + 0.1 * i);
      m.vertex_colors.push_back({static_cast<uint8_t>(16 * i), static_cast<uint8_t>(28 * j),
                                 static_cast<uint8_t>((7 * i + 3 * j) % 256)});
    }
  }
  auto id = [&](int i, int j) { return (i % n) * k + (j % k); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
}

ms::PointCloud SampleCloud() {
  ms::PointCloud c;
  for (int i = 0; i < 50; ++i) {
    const double t = 0.37 * i;
    c.points.emplace_back(std::cos(t) * 2.5, std::sin(t) / 3.0, 0.01 * i * i);
    c.normals.emplace_back(Eigen::Vector3d(std::cos(t), std::sin(t), 0.5).normalized());
    c.colors.push_back({static_cast<uint8_t>(5 * i), static_cast<uint8_t>(255 - 5 * i), 77});
    c.scalars.push_back(static_cast<float>(0.02 * i));
  }
  return c;
}

nlohmann::json ToJson(const ms::Mesh& m) {
  nlohmann::json j;
  for (const auto& v : m.vertices) j["vertices"].push_back({v.x(), v.y(), v.z()});
  for (const auto& f : m.faces) j["faces"].push_back({f[0], f[1], f[2]});
  for (const auto& c : m.vertex_colors) j["colors"].push_back({c[0], c[1], c[2]});
  return j;
}

nlohmann::json ToJson(const ms::PointCloud& c) {
  nlohmann::json j;
  for (const auto& v : c.points) j["points"].push_back({v.x(), v.y(), v.z()});
  for (const auto& n : c.normals) j["normals"].push_back({n.x(), n.y(), n.z()});
  for (const auto& k : c.colors) j["colors"].push_back({k[0], k[1], k[2]});
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUTPUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    const std::filesystem::path dir = argv[1];
    std::filesystem::create_directories(dir);
    const ms::Mesh mesh = SampleMesh();
    const ms::PointCloud cloud = SampleCloud();
    ms::MeshWriteOptions binary, ascii, binary_float;
    ascii.binary = false;
    binary_float.float_coordinates = true;
    ms::WriteMesh(mesh, (dir / "mesh_binary.ply").string(), binary);
    ms::WriteMesh(mesh, (dir / "mesh_ascii.ply").string(), ascii);
    ms::WriteMesh(mesh, (dir / "mesh_binary_float.ply").string(), binary_float);
    ms::WriteMesh(mesh, (dir / "mesh.obj").string());
    ms::WritePointCloud(cloud, (dir / "points_binary.ply").string(), binary);
    ms::WritePointCloud(cloud, (dir / "points_ascii.ply").string(), ascii);
    const nlohmann::json expected = {{"mesh", ToJson(mesh)}, {"points", ToJson(cloud)}};
    ms::WriteFileAtomically(
        dir / "expected.json", [&](std::ostream& os) { os << expected.dump() << "\n"; }, false);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mesh_io_sample_writer: %s\n", e.what());
    return 1;
  }
  return 0;
}
