// Throughput of the manifold reconstruction steps (docs/design/performance.md):
//   manifold_bench [points ...] [--insert N] [--threads N] [--export DIR] [--json FILE]
//                  [--manifold.* ...]
//   default sizes: 10^4 10^5 10^6; the manifold options are the library's (`--help` lists them)
// For each size: Delaunay insertion, ray tracing (rays/s), growing (cells/s), peak memory per
// point; then incremental insertion of N (default 10^4) points near the surface (points/s), in
// the coordinator's order (by camera, then pixel).
// --export=DIR writes, per size, the input points (PLY, normals = mean unit direction to the
// cameras that see each point, for the Poisson baseline), the initial manifold and the
// manifold after the incremental insertion.
// --json=FILE writes the rows as a JSON array, for bench/manifold_figures.py.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/option_registration.h"
#include "base/error.h"
#include "base/log.h"
#include "base/memory.h"
#include "bench/bench_scenes.h"
#include "manifold/delaunay_manifold.h"
#include "mesh/mesh_io.h"

namespace {

struct BenchOptions {
  std::vector<int64_t> sizes = {10000, 100000, 1000000};
  int64_t insert_count = 10000;
  int walk_threads = 0;  // one per core
  std::string export_dir;
  std::string json_path;
  ms::ManifoldOptions manifold;
};

// One blob of `n` points: build, then insert points near the surface as sweeping would; prints
// one table row and its details and returns them.
nlohmann::json RunSize(int64_t n, const BenchOptions& o) {
  const int64_t insert_count = o.insert_count;
  const std::string& export_dir = o.export_dir;
  const ms::bench::ManifoldBenchScene scene = ms::bench::MakeBlobScene(n, 48, 5, 42);
  const int64_t rss_before = ms::PeakRssBytes();
  ms::DelaunayManifold manifold(scene.cameras, o.manifold);
  manifold.set_walk_threads(o.walk_threads);
  ms::Timer timer;
  const ms::BuildStats stats = manifold.Build(scene.points);
  const double total = timer.Seconds();
  const int64_t rss = ms::PeakRssBytes() - rss_before;
  if (!export_dir.empty()) {
    ms::PointCloud cloud;
    for (const ms::RayPoint& p : scene.points) {
      Eigen::Vector3d towards = Eigen::Vector3d::Zero();
      for (int32_t c : p.cameras) towards += (scene.cameras[c].center - p.position).normalized();
      cloud.points.push_back(p.position);
      cloud.normals.push_back(towards.normalized());
    }
    const std::string stem = export_dir + "/blob_" + std::to_string(n);
    ms::WritePointCloud(cloud, stem + "_points.ply");
    ms::WriteMesh(manifold.ExtractSurface(), stem + "_manifold.ply");
  }
  // Incremental: new points near the surface, as sweeping would find them.
  ms::bench::ManifoldBenchScene more = ms::bench::MakeBlobScene(insert_count, 48, 3, 4242, 0.002);
  ms::bench::SortLikeTheCoordinator(scene.cameras, &more.points);
  timer.Restart();
  const ms::InsertionStats ins = manifold.Insert(more.points);
  const double insert_total = timer.Seconds();
  if (!export_dir.empty()) {
    ms::WriteMesh(manifold.ExtractSurface(),
                  export_dir + "/blob_" + std::to_string(n) + "_inserted.ply");
  }
  std::printf("%9lld %8lld %9lld %8.2f %9.2f %11.0f %8.2f %11.0f %9.2f %8.0f %10.0f %11.2f\n",
              static_cast<long long>(n), static_cast<long long>(stats.rays),
              static_cast<long long>(stats.cells), stats.seconds_triangulation,
              stats.seconds_ray_tracing, stats.rays / stats.seconds_ray_tracing,
              stats.seconds_growing, stats.outside_cells / std::max(stats.seconds_growing, 1e-9),
              total, static_cast<double>(rss) / n, insert_count / insert_total, insert_total);
  std::printf(
      "          %.1f cell steps per ray; %lld manifold tests, %lld full, %.1f link steps each\n",
      static_cast<double>(stats.ray_cell_steps) / std::max<int64_t>(stats.rays, 1),
      static_cast<long long>(stats.manifold_tests),
      static_cast<long long>(stats.full_manifold_tests),
      static_cast<double>(stats.link_steps) / std::max<int64_t>(stats.full_manifold_tests, 1));
  std::printf(
      "          incremental: %lld inserted, %lld discarded (conflict), %lld shrunk, "
      "%lld candidate rays, %lld re-walked (%.1f cells each), insertion %.2f s + regrowing %.2f "
      "s\n",
      static_cast<long long>(ins.inserted), static_cast<long long>(ins.discarded_conflict),
      static_cast<long long>(ins.shrunk_cells), static_cast<long long>(ins.candidate_rays),
      static_cast<long long>(ins.rewalked_rays),
      static_cast<double>(ins.rewalk_steps) / std::max<int64_t>(ins.rewalked_rays, 1),
      ins.seconds_insertion, ins.seconds_growing);
  // Not timed: a manifold test on every free cell next to O.
  std::printf("          after regrowing: %lld cells in O, %lld free cells could still join it\n",
              static_cast<long long>(manifold.num_outside_cells()),
              static_cast<long long>(manifold.num_joinable_cells()));
  return {{"points", n},
          {"rays", stats.rays},
          {"cells", stats.cells},
          {"seconds_triangulation", stats.seconds_triangulation},
          {"seconds_ray_tracing", stats.seconds_ray_tracing},
          {"seconds_growing", stats.seconds_growing},
          {"seconds_build", total},
          {"peak_rss_bytes_per_point", static_cast<double>(rss) / n},
          {"cell_steps_per_ray",
           static_cast<double>(stats.ray_cell_steps) / std::max<int64_t>(stats.rays, 1)},
          {"insert_count", insert_count},
          {"seconds_insert", insert_total},
          {"inserted", ins.inserted},
          {"discarded_conflict", ins.discarded_conflict},
          {"rewalked_rays", ins.rewalked_rays},
          {"cells_per_rewalked_ray",
           static_cast<double>(ins.rewalk_steps) / std::max<int64_t>(ins.rewalked_rays, 1)},
          {"seconds_insertion", ins.seconds_insertion},
          {"seconds_regrowing", ins.seconds_growing}};
}

}  // namespace

int main(int argc, char** argv) {
  ms::InitLogging("bench");
  spdlog::set_level(spdlog::level::warn);
  BenchOptions o;
  CLI::App cli(
      "The manifold's steps on synthetic blobs: Delaunay, ray tracing, growing, then "
      "incremental insertion (docs/design/performance.md)");
  cli.add_option("points", o.sizes, "point counts (>= 10), one run each")
      ->check(CLI::Range(int64_t{10}, int64_t{1} << 40))
      ->capture_default_str();
  cli.add_option("--insert", o.insert_count, "points inserted after the build")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cli.add_option("--threads", o.walk_threads, "ray-walking threads (0: one per core)")
      ->capture_default_str();
  cli.add_option("--export", o.export_dir, "write the points and meshes into this folder");
  cli.add_option("--json", o.json_path, "write the rows into this JSON file");
  ms::app::AddOptionGroup(&cli, &o.manifold);
  CLI11_PARSE(cli, argc, argv);
  try {
    o.manifold.Check();
  } catch (const ms::InputError& e) {
    std::fprintf(stderr, "manifold_bench: %s\n", e.what());
    return 2;
  }
  std::printf("%9s %8s %9s %8s %9s %11s %8s %11s %9s %8s %10s %11s\n", "points", "rays", "cells",
              "DT s", "trace s", "rays/s", "grow s", "cells/s", "total s", "B/point", "ins pts/s",
              "ins total s");
  nlohmann::json rows = nlohmann::json::array();
  for (int64_t n : o.sizes) {
    rows.push_back(RunSize(n, o));
    std::fflush(stdout);
  }
  if (!o.json_path.empty()) {
    std::ofstream json(o.json_path);
    json << rows.dump(1) << "\n";
    if (!json) {
      std::fprintf(stderr, "manifold_bench: cannot write %s\n", o.json_path.c_str());
      return 1;
    }
  }
  return 0;
}
