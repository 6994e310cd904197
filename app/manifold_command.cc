// `manisweep manifold`: the initial manifold alone (the paper's "initial mesh"), with timing
// per step; with --tiles, grown over spatial tiles in one process (tiles/tile_growth.h).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "app/commands.h"
#include "app/option_registration.h"
#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "manifold/delaunay_manifold.h"
#include "manifold/output_meshes.h"
#include "manifold/scene_rays.h"
#include "mesh/float_cleanup.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "scene/scene_io.h"
#include "tiles/tile_growth.h"
#include "tiles/tile_layout.h"

namespace ms::app {
namespace {

struct ManifoldCommandOptions {
  std::string input;
  std::string from = "auto";
  std::string output;
  std::string free_space_boundary;
  bool ascii = false;
  bool check = true;
  int tiles = 0;
  std::string tile_meshes;
  ManifoldOptions manifold;
};

// The independent check of a written mesh: a closed 2-manifold without self-intersections.
void CheckClosedManifold(const Mesh& mesh) {
  MeshCheckOptions check_options;
  check_options.check_self_intersections = mesh.NumFaces() < 2000000;
  const MeshReport report = CheckMesh(mesh, check_options);
  std::printf("  check-mesh        %s\n",
              report.is_closed_manifold ? "closed 2-manifold" : "NOT a closed 2-manifold");
  if (!report.is_closed_manifold) {
    for (const std::string& problem : report.Problems()) std::printf("    %s\n", problem.c_str());
    throw InternalError("the extracted surface is not a closed 2-manifold");
  }
}

void ThrowIfEmpty(const Mesh& mesh, const ManifoldCommandOptions& options) {
  if (!mesh.faces.empty()) return;
  throw InputError(options.input +
                   ": the manifold is empty: no cell reached the free-space "
                   "threshold (--manifold.free-threshold " +
                   std::to_string(options.manifold.free_threshold) + ") or none could grow");
}

// Each tile's faces as a mesh of its own (open along the seams), and the layout, into `dir`.
void WriteTileMeshes(const TiledScene& tiled, const TiledSurface& grown, const TileLayout& layout,
                     const std::string& dir, const MeshWriteOptions& write_options) {
  std::filesystem::create_directories(dir);
  const std::string json = layout.ToJson();
  WriteFileAtomically(
      dir + "/tiles.json", [&](std::ostream& out) { out << json; }, false);
  for (size_t t = 0; t < grown.tile_faces.size(); ++t) {
    Mesh piece;
    piece.vertices = tiled.points;
    piece.faces = grown.tile_faces[t];
    piece.RemoveUnreferencedVertices();
    WriteMesh(piece, dir + "/tile_" + std::to_string(t) + ".ply", write_options);
  }
}

// The initial manifold grown over `options.tiles` tiles, one after another in this process.
void RunTiledManifold(const ManifoldCommandOptions& options, const Scene& scene) {
  Timer timer;
  const TiledScene tiled = TiledSceneFromPoints(RayPointsFromScene(scene),
                                                ManifoldCamerasFromScene(scene), options.manifold);
  const TileLayout layout =
      TileLayout::Split(std::vector<Eigen::Vector3d>(tiled.points.begin(),
                                                     tiled.points.begin() + tiled.first_steiner),
                        options.tiles);
  const TiledSurface grown = GrowTiles(tiled, layout, options.manifold);
  Mesh mesh;
  mesh.vertices = tiled.points;
  mesh.faces = grown.faces;
  ThrowIfEmpty(mesh, options);
  // Steiner points are scaffolding: a cleanup collapse keeps the point over them.
  std::vector<uint8_t> scaffold(mesh.vertices.size(), 0);
  std::fill(scaffold.begin() + tiled.first_steiner, scaffold.end(), 1);
  FloatCleanupStats cleanup;
  if (options.manifold.float_cleanup) {
    cleanup = CleanForFloatingPoint(&mesh, &scaffold);
  } else {
    mesh.RemoveUnreferencedVertices();
  }
  const double total = timer.Seconds();
  MeshWriteOptions write_options;
  write_options.binary = !options.ascii;
  WriteMesh(mesh, options.output, write_options);
  const TileGrowthStats& stats = grown.stats;
  std::printf("initial manifold of %s over %d tiles\n", options.input.c_str(), options.tiles);
  std::printf("  points            %d (+%zu Steiner), %zu rays\n", tiled.first_steiner,
              tiled.points.size() - tiled.first_steiner, tiled.rays.size());
  std::printf("  seams             %lld points held beyond the tiles' own, %.3f s\n",
              static_cast<long long>(stats.foreign_points), stats.seconds_exchange);
  std::printf("  ray counts        %.3f s\n", stats.seconds_counting);
  std::printf(
      "  growing           %d colours, %d rounds, %d of camera repairs, %d of pocket joins, "
      "%.3f s\n",
      stats.colours, stats.rounds, stats.camera_rounds, stats.pocket_rounds, stats.seconds_growing);
  std::printf("  surface           %zu vertices, %zu faces\n", mesh.NumVertices(), mesh.NumFaces());
  if (options.manifold.float_cleanup) {
    std::printf("  float cleanup     %lld problems -> %lld, %.3f s\n",
                static_cast<long long>(cleanup.problems_before),
                static_cast<long long>(cleanup.problems_after), cleanup.seconds);
  }
  std::printf("  total             %.3f s; wrote %s\n", total, options.output.c_str());
  if (!options.tile_meshes.empty()) {
    WriteTileMeshes(tiled, grown, layout, options.tile_meshes, write_options);
    std::printf("  tiles             wrote %s/tiles.json and tile_<n>.ply\n",
                options.tile_meshes.c_str());
  }
  if (options.check) CheckClosedManifold(mesh);
}

void RunManifold(const ManifoldCommandOptions& options) {
  options.manifold.Check();
  SceneReadOptions read_options;
  const Scene scene = ReadScene(options.input, read_options, ParseSceneFormat(options.from));
  if (scene.points.empty()) throw InputError(options.input + ": the scene has no points");
  if (scene.NumObservations() == 0) {
    throw InputError(options.input + ": no point has visibility (observations)");
  }
  if (options.tiles > 0) {
    RunTiledManifold(options, scene);
    return;
  }
  if (!options.tile_meshes.empty()) throw InputError("--tile-meshes needs --tiles");
  Timer timer;
  DelaunayManifold manifold(ManifoldCamerasFromScene(scene), options.manifold);
  const BuildStats stats = manifold.Build(RayPointsFromScene(scene));
  SurfaceInfo info;
  Mesh extracted = manifold.ExtractSurface(&info);
  ThrowIfEmpty(extracted, options);
  const OutputMeshes output =
      MakeOutputMeshes(manifold, std::move(extracted), info, options.manifold.float_cleanup);
  const Mesh& mesh = output.closed;
  const double total = timer.Seconds();
  MeshWriteOptions write_options;
  write_options.binary = !options.ascii;
  WriteMesh(mesh, options.output, write_options);
  std::printf("initial manifold of %s\n", options.input.c_str());
  std::printf("  points            %lld (+%lld Steiner, %lld merged duplicates)\n",
              static_cast<long long>(stats.points), static_cast<long long>(stats.steiner_points),
              static_cast<long long>(stats.merged_duplicates));
  std::printf("  Delaunay          %lld cells, %.3f s\n", static_cast<long long>(stats.cells),
              stats.seconds_triangulation);
  std::printf("  ray tracing       %lld rays, %.1f cells per ray, %.3f s\n",
              static_cast<long long>(stats.rays),
              stats.rays ? static_cast<double>(stats.ray_cell_steps) / stats.rays : 0.0,
              stats.seconds_ray_tracing);
  std::printf(
      "  growing           %lld of %lld free cells outside (%lld pockets joined, with %lld "
      "pinching slivers), %.3f s\n",
      static_cast<long long>(stats.outside_cells), static_cast<long long>(stats.free_cells),
      static_cast<long long>(stats.pockets_joined), static_cast<long long>(stats.slivers_joined),
      stats.seconds_growing);
  const std::vector<int32_t> enclosed = manifold.CamerasInMatter();
  std::printf(
      "  cameras           %zu in the matter%s (%lld vertex stars completed to free cameras)\n",
      enclosed.size(), enclosed.empty() ? "" : ": they see the mesh from inside",
      static_cast<long long>(stats.camera_stars_completed));
  std::printf("  surface           %zu vertices (%lld Steiner), %zu faces\n", mesh.NumVertices(),
              static_cast<long long>(info.steiner_vertices), mesh.NumFaces());
  if (options.manifold.float_cleanup) {
    const FloatCleanupStats& c = output.cleanup;
    std::printf(
        "  float cleanup     %lld problems -> %lld: %lld collapses, %lld splits, %lld moves, "
        "%.3f s\n",
        static_cast<long long>(c.problems_before), static_cast<long long>(c.problems_after),
        static_cast<long long>(c.collapses), static_cast<long long>(c.splits),
        static_cast<long long>(c.moves), c.seconds);
  }
  std::printf("  total             %.3f s; wrote %s\n", total, options.output.c_str());
  if (!options.free_space_boundary.empty()) {
    const Mesh boundary = manifold.ExtractFreeSpaceBoundary();
    WriteMesh(boundary, options.free_space_boundary, write_options);
    std::printf(
        "  free space        %lld free cells (%lld not in O), boundary %zu faces; wrote %s\n",
        static_cast<long long>(stats.free_cells),
        static_cast<long long>(stats.free_cells_left_inside), boundary.NumFaces(),
        options.free_space_boundary.c_str());
  }
  if (options.check) CheckClosedManifold(mesh);
}

}  // namespace

void RegisterManifoldCommand(CLI::App& app) {
  auto options = std::make_shared<ManifoldCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "manifold",
      "The initial manifold alone: Delaunay triangulation, visibility ray tracing and manifold "
      "growing (paper section 2.1), with timing per step");
  cmd->add_option("-i,--input", options->input, "scene with points and visibility")->required();
  cmd->add_option("--from", options->from, "input format (see `manisweep convert --help`)")
      ->capture_default_str();
  cmd->add_option("-o,--output", options->output, "mesh to write (.ply or .obj)")->required();
  cmd->add_option("--free-space-boundary", options->free_space_boundary,
                  "also write the boundary of every free cell, in O or not: what the visibility "
                  "alone gives before growing keeps the surface manifold (generally not a "
                  "manifold; for diagnosis)");
  cmd->add_flag("--ascii", options->ascii, "write ASCII PLY instead of binary");
  cmd->add_flag("!--no-check", options->check, "skip the independent manifold check of the result");
  cmd->add_option("--tiles", options->tiles,
                  "grow the manifold over this many spatial tiles, one after another in this "
                  "process, and write their surfaces as one mesh (0: one triangulation; "
                  "docs/design/scalability.md, \"Tiles\")")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  cmd->add_option("--tile-meshes", options->tile_meshes,
                  "with --tiles: write each tile's faces (tile_<n>.ply) and the layout "
                  "(tiles.json) into this directory");
  AddOptionGroup(cmd, &options->manifold);
  cmd->callback([options] { RunManifold(*options); });
}

}  // namespace ms::app
