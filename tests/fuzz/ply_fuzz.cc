// libFuzzer target for the PLY reader (mesh and point-cloud paths) and the mesh checker. Any input
// must either parse or throw ms::InputError; anything else (a crash, a sanitizer report, another
// exception, a huge allocation) is a finding. Build with -DMANISWEEP_FUZZ=ON (clang), run e.g.
//   build-fuzz/mesh/ply_fuzz -max_total_time=60 -rss_limit_mb=2048 corpus/
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "base/error.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const ms::Mesh mesh = ms::ParseMesh(bytes, ms::MeshFormat::kPly, "fuzz.ply");
    // Every face index the reader returns must be usable.
    for (const auto& f : mesh.faces) {
      for (int32_t v : f) {
        if (v < 0 || static_cast<size_t>(v) >= mesh.vertices.size()) __builtin_trap();
      }
    }
    if (mesh.HasColors() && mesh.vertex_colors.size() != mesh.vertices.size()) __builtin_trap();
    // The checker must digest whatever the reader accepts (non-manifold, degenerate, ...).
    if (mesh.NumFaces() <= 4096) {
      const ms::MeshReport report = ms::CheckMesh(mesh);
      if (report.is_valid && !report.Problems().empty()) __builtin_trap();
      if (report.ToJson().empty() || report.ToTable().empty()) __builtin_trap();
    }
  } catch (const ms::InputError&) {
  }
  try {
    const ms::PointCloud cloud = ms::ParsePointCloud(bytes, "fuzz.ply");
    const size_t n = cloud.points.size();
    if ((!cloud.normals.empty() && cloud.normals.size() != n) ||
        (!cloud.colors.empty() && cloud.colors.size() != n) ||
        (!cloud.scalars.empty() && cloud.scalars.size() != n)) {
      __builtin_trap();
    }
  } catch (const ms::InputError&) {
  }
  return 0;
}
