#include "sweep/reference_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "base/log.h"

namespace ms {

std::vector<Eigen::Vector3d> FaceNormals(const Mesh& mesh) {
  std::vector<Eigen::Vector3d> normals(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) normals[f] = mesh.FaceNormal(f);
  return normals;
}

std::vector<std::array<Eigen::Vector3d, 3>> SweepFacets(const Mesh& mesh,
                                                        const std::vector<Eigen::Vector3d>& normals,
                                                        const Eigen::Vector3d& center,
                                                        double alpha_k) {
  std::vector<std::array<Eigen::Vector3d, 3>> soup(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int i = 0; i < 3; ++i) {
      soup[f][i] = SweepVertex(mesh.vertices[mesh.faces[f][i]], normals[f], center, alpha_k);
    }
  }
  return soup;
}

void RenderSoup(const std::vector<std::array<Eigen::Vector3d, 3>>& soup,
                SoftwareRasterizer* raster) {
  raster->Clear();
  for (size_t f = 0; f < soup.size(); ++f) {
    raster->DrawTriangle(soup[f][0], soup[f][1], soup[f][2], static_cast<int32_t>(f));
  }
}

void ReprojectNeighbour(const SoftwareRasterizer& camera_raster, const View& neighbour,
                        const cv::Mat& neighbour_image, const SoftwareRasterizer& shadow_map,
                        double occlusion_tolerance, cv::Mat* reprojected, cv::Mat* mask) {
  const int width = camera_raster.width(), height = camera_raster.height();
  reprojected->create(height, width, CV_32F);
  mask->create(height, width, CV_8U);
  reprojected->setTo(0);
  mask->setTo(0);
  const Intrinsics& k = neighbour.intrinsics;
  const int nw = neighbour_image.cols, nh = neighbour_image.rows;
  const std::vector<double>& depth = camera_raster.depth();
  const std::vector<Eigen::Vector3d>& world = camera_raster.world();
  const std::vector<double>& shadow = shadow_map.depth();
  for (int row = 0; row < height; ++row) {
    float* out = reprojected->ptr<float>(row);
    uint8_t* valid = mask->ptr<uint8_t>(row);
    for (int col = 0; col < width; ++col) {
      const size_t index = camera_raster.Index(col, row);
      if (!(depth[index] < SoftwareRasterizer::kEmpty)) continue;
      const Eigen::Vector3d x = neighbour.R * world[index] + neighbour.t;
      if (!(x.z() > 0)) continue;
      const double u = k.fx * x.x() / x.z() + k.cx;
      const double v = k.fy * x.y() / x.z() + k.cy;
      if (!(u >= 0.5 && u <= nw - 0.5 && v >= 0.5 && v <= nh - 0.5)) continue;
      const int tu = std::min(static_cast<int>(u), nw - 1);
      const int tv = std::min(static_cast<int>(v), nh - 1);
      if (!(x.z() <= shadow[shadow_map.Index(tu, tv)] * (1 + occlusion_tolerance))) continue;
      const double sx = u - 0.5, sy = v - 0.5;
      const int x0 = std::min(static_cast<int>(sx), nw - 1);
      const int y0 = std::min(static_cast<int>(sy), nh - 1);
      const int x1 = std::min(x0 + 1, nw - 1), y1 = std::min(y0 + 1, nh - 1);
      const double fx = sx - x0, fy = sy - y0;
      const float* r0 = neighbour_image.ptr<float>(y0);
      const float* r1 = neighbour_image.ptr<float>(y1);
      const double top = r0[x0] + fx * (r0[x1] - r0[x0]);
      const double bottom = r1[x0] + fx * (r1[x1] - r1[x0]);
      out[col] = static_cast<float>(top + fy * (bottom - top));
      valid[col] = 255;
    }
  }
}

namespace {
constexpr double kVarianceFloor = 1e-5;  // relative to the mean square: float round-off
}  // namespace

int64_t WeightedNcc(const cv::Mat& I, const cv::Mat& J, const cv::Mat& mask, const cv::Mat& window,
                    double min_texture_variance, double min_window_weight, cv::Mat* ncc) {
  CV_Assert(I.type() == CV_32F && J.type() == CV_32F && mask.type() == CV_8U);
  CV_Assert(I.size() == J.size() && I.size() == mask.size());
  cv::Mat m;
  mask.convertTo(m, CV_32F, 1.0 / 255.0);
  cv::Mat mi, mj;
  cv::subtract(I, cv::Scalar(0.5), mi);
  cv::subtract(J, cv::Scalar(0.5), mj);
  mi = mi.mul(m);
  mj = mj.mul(m);
  cv::Mat ii = mi.mul(mi), jj = mj.mul(mj), ij = mi.mul(mj);
  const auto blur = [&](const cv::Mat& src) {
    cv::Mat dst;
    cv::sepFilter2D(src, dst, CV_32F, window.t(), window, cv::Point(-1, -1), 0,
                    cv::BORDER_CONSTANT);
    return dst;
  };
  const cv::Mat bw = blur(m), bi = blur(mi), bj = blur(mj);
  const cv::Mat bii = blur(ii), bjj = blur(jj), bij = blur(ij);
  ncc->create(I.size(), CV_32F);
  int64_t defined = 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int row = 0; row < I.rows; ++row) {
    float* out = ncc->ptr<float>(row);
    const uint8_t* valid = mask.ptr<uint8_t>(row);
    const float* w = bw.ptr<float>(row);
    const float *si = bi.ptr<float>(row), *sj = bj.ptr<float>(row);
    const float *sii = bii.ptr<float>(row), *sjj = bjj.ptr<float>(row), *sij = bij.ptr<float>(row);
    for (int col = 0; col < I.cols; ++col) {
      out[col] = nan;
      if (!valid[col] || !(w[col] >= min_window_weight)) continue;
      const double inv_w = 1.0 / w[col];
      const double mean_i = si[col] * inv_w, mean_j = sj[col] * inv_w;
      const double var_i = sii[col] * inv_w - mean_i * mean_i;
      const double var_j = sjj[col] * inv_w - mean_j * mean_j;
      // Below the float precision floor a variance is zero (a constant window).
      const double floor_i = std::max(min_texture_variance, kVarianceFloor * sii[col] * inv_w);
      const double floor_j = std::max(min_texture_variance, kVarianceFloor * sjj[col] * inv_w);
      if (!(var_i > floor_i && var_j > floor_j)) continue;
      const double cov = sij[col] * inv_w - mean_i * mean_j;
      out[col] = static_cast<float>(std::clamp(cov / std::sqrt(var_i * var_j), -1.0, 1.0));
      ++defined;
    }
  }
  return defined;
}

SweepResult ReferenceSweepKernel::Run(const SweepJob& job) {
  Timer total;
  Timer stage;
  const PreparedSweep prep = PrepareSweep(job);
  const SweepOptions& options = job.options;
  SweepResult result;
  result.stats = PreparedSweepStats(prep);
  SweepStats& stats = result.stats;
  const View& view = prep.camera.view;
  const int num_neighbours = static_cast<int>(prep.neighbours.size());

  const std::vector<Eigen::Vector3d> normals = FaceNormals(job.mesh);
  const Eigen::Vector3d center = view.Center();
  SoftwareRasterizer camera_raster(view, prep.near, /*keep_world=*/true);
  std::vector<SoftwareRasterizer> shadow_maps;
  for (const SweepCamera& n : prep.neighbours) {
    shadow_maps.emplace_back(n.view, prep.near, /*keep_world=*/false);
  }
  std::vector<TileWinner> best(prep.tiles.NumTiles());
  const WinnerRule rule = WinnerRule::For(options, num_neighbours);
  stats.prepare_s = stage.Seconds();

  // Offset k's mesh rendered from C and every neighbour's NCC against C into *ncc.
  cv::Mat reprojected, mask;
  const auto sweep = [&](int k, std::vector<cv::Mat>* ncc) {
    stage.Restart();
    const auto soup = SweepFacets(job.mesh, normals, center, prep.alpha * k);
    RenderSoup(soup, &camera_raster);
    for (int j = 0; j < num_neighbours; ++j) RenderSoup(soup, &shadow_maps[j]);
    for (int32_t f : camera_raster.face()) stats.covered_pixels += f >= 0;
    stats.raster_s += stage.Seconds();
    ncc->resize(num_neighbours);
    for (int j = 0; j < num_neighbours; ++j) {
      stage.Restart();
      ReprojectNeighbour(camera_raster, prep.neighbours[j].view, prep.neighbours[j].image,
                         shadow_maps[j], options.occlusion_tolerance, &reprojected, &mask);
      stats.reproject_s += stage.Seconds();
      stage.Restart();
      stats.valid_hypotheses +=
          WeightedNcc(prep.camera.image, reprojected, mask, prep.window,
                      options.min_texture_variance, options.min_window_weight, &(*ncc)[j]);
      stats.ncc_s += stage.Seconds();
    }
  };
  const auto pointers = [](const std::vector<cv::Mat>& maps) {
    std::vector<const float*> out;
    for (const cv::Mat& m : maps) out.push_back(m.ptr<float>());
    return out;
  };
  std::vector<cv::Mat> surface_ncc, ncc;
  if (rule.must_move) sweep(0, &surface_ncc);
  const std::vector<const float*> surface = pointers(surface_ncc);
  for (const int k : CompetingOffsets(prep, rule)) {
    sweep(k, &ncc);
    // Tile-best (sweep_kernel.h): ties go to the smaller k, neighbour, pixel.
    stage.Restart();
    UpdateTileWinners(prep.tiles, k, pointers(ncc), surface, camera_raster.face().data(),
                      camera_raster.world().data(), rule, &best);
    stats.reduce_s += stage.Seconds();
  }

  for (const TileWinner& tile : best) {
    if (tile.neighbour >= 0) result.points.push_back(MakeSweepPoint(tile, prep));
  }
  stats.total_s = total.Seconds();
  return result;
}

}  // namespace ms
