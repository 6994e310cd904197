// Throughput of the manifold reconstruction steps (docs/design/performance.md):
//   manifold_bench [points ...] [--insert=N] [--export=DIR] [--graded-steiner=hidden|on|off]
//                  [--steiner-grid=N] [--steiner-min-spacing=X] [--steiner-clearance=X]
//                  [--regrow-seeds=boundary|changed] [--join-pockets=on|off] [--threads=N]
//   default Steiner mode: the library's (hidden graded points, at every size)
//   default sizes: 10^4 10^5 10^6
// For each size: Delaunay insertion, ray tracing (rays/s), growing (cells/s), peak memory per
// point; then incremental insertion of N (default 10^4) points near the surface (points/s), in
// the coordinator's order (by camera, then pixel).
// --export=DIR writes, per size, the input points (PLY, normals = mean unit direction to the
// cameras that see each point, for the Poisson baseline), the initial manifold and the
// manifold after the incremental insertion.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/log.h"
#include "base/memory.h"
#include "bench/bench_scenes.h"
#include "manifold/delaunay_manifold.h"
#include "mesh/mesh_io.h"

int main(int argc, char** argv) {
  ms::InitLogging("bench");
  spdlog::set_level(spdlog::level::warn);
  std::vector<int64_t> sizes;
  int64_t insert_count = 10000;
  int walk_threads = 0;  // one per core
  std::string export_dir;
  ms::ManifoldOptions options;
  const char* usage =
      "usage: manifold_bench [points ...] [--insert=N] [--export=DIR] "
      "[--graded-steiner=hidden|on|off] [--steiner-grid=N] [--steiner-min-spacing=X] "
      "[--steiner-clearance=X] [--regrow-seeds=boundary|changed] [--join-pockets=on|off] "
      "[--threads=N]\n";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::printf("%s", usage);
      return 0;
    }
    if (arg.rfind("--", 0) == 0 && arg.find('=') == std::string::npos) {
      std::fprintf(stderr, "manifold_bench: unknown option %s\n%s", arg.c_str(), usage);
      return 2;
    }
    try {
      if (arg.rfind("--insert=", 0) == 0) {
        insert_count = std::stoll(arg.substr(9));
      } else if (arg.rfind("--threads=", 0) == 0) {
        walk_threads = std::stoi(arg.substr(10));
      } else if (arg.rfind("--export=", 0) == 0) {
        export_dir = arg.substr(9);
      } else if (arg.rfind("--steiner-min-spacing=", 0) == 0) {
        options.steiner_min_spacing = std::stod(arg.substr(22));
      } else if (arg.rfind("--steiner-clearance=", 0) == 0) {
        options.steiner_clearance = std::stod(arg.substr(20));
      } else if (arg.rfind("--steiner-grid=", 0) == 0) {
        options.steiner_grid = std::stoi(arg.substr(15));
      } else if (arg.rfind("--graded-steiner=", 0) == 0) {
        const std::string scheme = arg.substr(17);
        bool known = false;
        for (const auto& [name, value] : ms::OptionChoices(ms::GradedSteiner{})) {
          if (scheme == name) {
            options.steiner_graded = value;
            known = true;
          }
        }
        if (!known) {
          std::fprintf(stderr, "manifold_bench: unknown --graded-steiner=%s\n%s", scheme.c_str(),
                       usage);
          return 2;
        }
      } else if (arg == "--regrow-seeds=boundary") {
        options.regrow_seeds = ms::RegrowSeeds::kBoundary;
      } else if (arg == "--regrow-seeds=changed") {
        options.regrow_seeds = ms::RegrowSeeds::kChanged;
      } else if (arg == "--join-pockets=on" || arg == "--join-pockets=off") {
        options.join_pockets = arg == "--join-pockets=on";
      } else {
        char* end = nullptr;
        const long long n = std::strtoll(arg.c_str(), &end, 10);
        if (end == arg.c_str() || *end != '\0' || n < 10) {
          std::fprintf(stderr, "manifold_bench: %s is not a point count (>= 10)\n%s", arg.c_str(),
                       usage);
          return 2;
        }
        sizes.push_back(n);
      }
    } catch (const std::exception&) {
      std::fprintf(stderr, "manifold_bench: bad value in %s\n%s", arg.c_str(), usage);
      return 2;
    }
  }
  if (sizes.empty()) sizes = {10000, 100000, 1000000};
  std::printf("%9s %8s %9s %8s %9s %11s %8s %11s %9s %8s %10s %11s\n", "points", "rays", "cells",
              "DT s", "trace s", "rays/s", "grow s", "cells/s", "total s", "B/point", "ins pts/s",
              "ins total s");
  for (int64_t n : sizes) {
    const ms::bench::ManifoldBenchScene scene = ms::bench::MakeBlobScene(n, 48, 5, 42);
    const int64_t rss_before = ms::PeakRssBytes();
    ms::DelaunayManifold manifold(scene.cameras, options);
    manifold.set_walk_threads(walk_threads);
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
    std::fflush(stdout);
  }
  return 0;
}
