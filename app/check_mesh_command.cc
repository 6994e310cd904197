// `manisweep check-mesh MESH`: the independent manifold checker (mesh/mesh_checker.h) on a file.
// Exit 0: valid; 3: the file reads fine but the mesh is not a valid manifold; 2: unreadable.
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "app/commands.h"
#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"

namespace ms::app {
namespace {

// Exit code for "read fine, not a valid manifold" (0 valid, 2 unreadable; see
// docs/reference/mesh-checker.md).
constexpr int kExitNotManifold = 3;

struct CheckMeshCommandOptions {
  std::string mesh;
  std::string json;
  bool no_self_intersections = false;
  MeshCheckOptions check;
};

int RunCheckMesh(const CheckMeshCommandOptions& options) {
  MeshCheckOptions check = options.check;
  check.check_self_intersections = !options.no_self_intersections;
  check.Check();
  const Timer timer;
  const Mesh mesh = ReadMesh(options.mesh);
  const MeshReport report = CheckMesh(mesh, check);
  spdlog::debug("check-mesh: {} checked in {:.2f} s", options.mesh, timer.Seconds());
  // With `--json -` stdout carries only the JSON (for jq and scripts); the table goes to stderr.
  const bool json_to_stdout = options.json == "-";
  std::fputs(report.ToTable(options.mesh).c_str(), json_to_stdout ? stderr : stdout);
  if (json_to_stdout) {
    std::fputs(report.ToJson(options.mesh).c_str(), stdout);
  } else if (!options.json.empty()) {
    const std::string json = report.ToJson(options.mesh);
    WriteFileAtomically(
        options.json, [&](std::ostream& os) { os << json; }, /*binary=*/false);
  }
  std::fflush(stdout);
  return report.is_valid ? kExitOk : kExitNotManifold;
}

}  // namespace

void RegisterCheckMeshCommand(CLI::App& app) {
  auto options = std::make_shared<CheckMeshCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "check-mesh",
      "Check that a mesh file (.ply/.obj) is a closed, oriented 2-manifold without "
      "self-intersections, exactly and in double precision. Reads only the file. Exit 0: valid; "
      "3: readable but not valid; 2: unreadable.");
  cmd->add_option("mesh", options->mesh, "mesh file (.ply or .obj)")->required();
  cmd->add_flag("--allow-boundary", options->check.allow_boundary,
                "accept a manifold with boundary (open fans) as valid")
      ->capture_default_str();
  cmd->add_option(
      "--json", options->json,
      "also write the report as JSON to this file ('-': stdout, the table then goes to stderr)");
  cmd->add_flag("--no-self-intersections", options->no_self_intersections,
                "skip every face-pair test: the exact self-intersection test and the "
                "floating-point close-pair and intersection tests (the only slow checks)")
      ->capture_default_str();
  cmd->add_option("--float-tolerance", options->check.float_tolerance,
                  "floating-point robustness: vertices, and faces sharing no vertex, closer than "
                  "this times the bounding-box diagonal make the mesh not valid")
      ->capture_default_str();
  cmd->add_option("--float-tolerance-abs", options->check.float_tolerance_abs,
                  "the same tolerance in mesh units; > 0 replaces --float-tolerance")
      ->capture_default_str();
  cmd->add_flag("--allow-float-issues", options->check.allow_float_issues,
                "report near-coincident vertices, close face pairs and double-precision "
                "intersections, but accept them as valid")
      ->capture_default_str();
  cmd->add_option("--max-examples", options->check.max_examples,
                  "indices listed per kind of problem")
      ->capture_default_str();
  cmd->add_option("--max-self-intersections", options->check.max_self_intersections,
                  "stop searching after this many intersecting face pairs")
      ->capture_default_str();
  cmd->callback([options] {
    const int code = RunCheckMesh(*options);
    // main() maps only exceptions to exit codes; "not manifold" is a result, not an error.
    if (code != kExitOk) std::exit(code);
  });
}

}  // namespace ms::app
