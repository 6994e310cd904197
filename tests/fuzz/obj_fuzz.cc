// libFuzzer target for the OBJ reader and the mesh checker. Any input must either parse or throw
// ms::InputError. Build with -DMANISWEEP_FUZZ=ON (clang), run e.g.
//   build-fuzz/mesh/obj_fuzz -max_total_time=60 -rss_limit_mb=2048 corpus/
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "base/error.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const ms::Mesh mesh = ms::ParseMesh(bytes, ms::MeshFormat::kObj, "fuzz.obj");
    for (const auto& f : mesh.faces) {
      for (int32_t v : f) {
        if (v < 0 || static_cast<size_t>(v) >= mesh.vertices.size()) __builtin_trap();
      }
    }
    for (const auto& v : mesh.vertices) {
      if (!v.allFinite()) __builtin_trap();
    }
    // The checker must digest whatever the reader accepts (non-manifold, degenerate, ...).
    if (mesh.NumFaces() <= 4096) {
      const ms::MeshReport report = ms::CheckMesh(mesh);
      if (report.is_valid && !report.Problems().empty()) __builtin_trap();
      if (report.ToJson().empty() || report.ToTable().empty()) __builtin_trap();
    }
  } catch (const ms::InputError&) {
  }
  return 0;
}
