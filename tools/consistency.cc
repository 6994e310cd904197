#include "tools/consistency.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "base/check.h"
#include "base/error.h"
#include "base/log.h"
#include "mesh/visible_mesh.h"
#include "sweep/cpu_sweep.h"
#include "sweep/software_raster.h"
#include "sweep/sweep_images.h"

namespace ms {
namespace {

// 1 where `mask` covers a pixel of `view` (at the swept resolution), else 0; every pixel without
// a mask.
std::vector<uint8_t> MaskPixels(const Mesh* mask, const View& view, double near) {
  std::vector<uint8_t> inside(static_cast<size_t>(view.intrinsics.width) * view.intrinsics.height,
                              1);
  if (mask == nullptr) return inside;
  const Mesh visible = ExtractVisibleMesh(*mask, view).mesh;
  SoftwareRasterizer raster(view, near, /*keep_world=*/false);
  for (size_t f = 0; f < visible.NumFaces(); ++f) {
    const auto& face = visible.faces[f];
    raster.DrawTriangle(visible.vertices[face[0]], visible.vertices[face[1]],
                        visible.vertices[face[2]], static_cast<int32_t>(f));
  }
  for (size_t i = 0; i < inside.size(); ++i) inside[i] = raster.depth()[i] < raster.kEmpty;
  return inside;
}

// The diagonal of the mesh's bounding box.
double MeshExtent(const Mesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : mesh.vertices) box.extend(v);
  return mesh.vertices.empty() ? 1.0 : box.diagonal().norm();
}

}  // namespace

double ConsistencyReport::ConsistentShare() const {
  return total.pixels > 0 ? static_cast<double>(total.consistent) / total.pixels : 0.0;
}

std::string ConsistencyReport::ToTable() const {
  const auto share = [](int64_t part, int64_t whole) {
    return whole > 0 ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
  };
  const auto line = [&](const std::string& name, const CameraConsistency& c) {
    return fmt::format("{:<8} {:>10} {:>8.1f}% {:>9.1f}% {:>10.1f}% {:>10.1f}%\n", name, c.pixels,
                       share(c.consistent, c.pixels), share(c.covered, c.pixels),
                       share(c.consistent, c.covered), share(c.consistent, c.defined));
  };
  std::string table = fmt::format("{:<8} {:>10} {:>9} {:>10} {:>11} {:>11}\n", "camera", "pixels",
                                  "consistent", "covered", "of covered", "of defined");
  for (const CameraConsistency& c : cameras) table += line(std::to_string(c.camera), c);
  table += line("all", total);
  return table;
}

ConsistencyReport MeasureConsistency(const Scene& scene, const Mesh& mesh,
                                     const ConsistencyOptions& options, const Mesh* within) {
  if (!(options.ncc_threshold > -1 && options.ncc_threshold < 1)) {
    throw InputError(
        fmt::format("consistency threshold must be in (-1, 1), got {}", options.ncc_threshold));
  }
  options.sweep.Check();
  options.neighbours.Check();
  ConsistencyReport report;
  Timer timer;
  const int num_views = static_cast<int>(scene.views.size());
  Progress progress("consistency: cameras", num_views);
  for (int c = 0; c < num_views; ++c) {
    progress.Update(c);
    const std::vector<int> neighbours = SelectNeighbours(scene, c, options.neighbours);
    if (neighbours.empty()) continue;
    SweepJob job;
    job.camera = LoadSweepCamera(c, scene.views[c]);
    for (int n : neighbours) job.neighbours.push_back(LoadSweepCamera(n, scene.views[n]));
    job.mesh = ExtractVisibleMesh(mesh, job.camera.view).mesh;
    job.options = options.sweep;
    job.options.num_offsets = 1;
    CameraConsistency result;
    result.camera = c;
    if (job.mesh.NumFaces() == 0) {  // the mesh is entirely out of view: nothing is consistent
      const Intrinsics& k = job.camera.view.intrinsics;
      const int level = SweepPyramidLevel(std::max(k.width, k.height), options.sweep);
      // No mesh gives the near plane here; the mask only needs one in front of the camera.
      const double near = 1e-9 * (within ? MeshExtent(*within) : 1.0);
      for (uint8_t in : MaskPixels(within, CameraAtPyramidLevel(job.camera, level).view, near)) {
        result.pixels += in;
      }
      report.cameras.push_back(result);
      continue;
    }
    const PreparedSweep prep = PrepareSweep(job);
    const std::vector<uint8_t> inside = MaskPixels(within, prep.camera.view, prep.near);
    for (uint8_t in : inside) result.pixels += in;
    CpuSweepSlab slab(job, prep);
    slab.Render(0);
    const LargeBuffer<int32_t>& faces = slab.faces();
    const size_t pixels = faces.size();
    MS_CHECK(pixels == inside.size()) << "mask of " << inside.size() << " pixels for " << pixels;
    std::vector<float> best(pixels, -INFINITY), ncc(pixels);
    std::vector<uint8_t> defined(pixels, 0);
    for (size_t j = 0; j < prep.neighbours.size(); ++j) {
      slab.Reproject(static_cast<int>(j));
      slab.Ncc(ncc.data());
      for (size_t i = 0; i < pixels; ++i) {
        if (std::isnan(ncc[i])) continue;
        defined[i] = 1;
        best[i] = std::max(best[i], ncc[i]);
      }
    }
    for (size_t i = 0; i < pixels; ++i) {
      if (!inside[i]) continue;
      result.covered += faces[i] >= 0;
      result.defined += defined[i];
      result.consistent += best[i] > options.ncc_threshold;
    }
    report.cameras.push_back(result);
    spdlog::debug("consistency: camera {}/{}: {:.1f}% of {} pixels consistent ({:.1f} s)", c + 1,
                  num_views, 100.0 * result.consistent / std::max<int64_t>(1, result.pixels),
                  result.pixels, timer.Seconds());
  }
  progress.Finish(num_views);
  for (const CameraConsistency& c : report.cameras) {
    report.total.pixels += c.pixels;
    report.total.covered += c.covered;
    report.total.defined += c.defined;
    report.total.consistent += c.consistent;
  }
  return report;
}

}  // namespace ms
