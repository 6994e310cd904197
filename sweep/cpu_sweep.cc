#include "sweep/cpu_sweep.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "base/log.h"
#include "sweep/reference_sweep.h"
#include "sweep/vector_clones.h"

#if MS_HAVE_AVX2_DISPATCH
#include <immintrin.h>
#endif

namespace ms {
namespace {

// C's camera frame to a neighbour's pixels, for reprojecting C's pixel rays.
struct ReprojectionRow {
  // A r(col) = ray0 + col ray_dx with A = R_n R_c^T and r = K_c^-1 (col + .5, row + .5, 1).
  float ray0[3], ray_dx[3];
  float b[3];  // t_n - A t_c
  float fx, fy, cx, cy;
  int width, height;      // the neighbour's image
  float max_depth_ratio;  // 1 + occlusion tolerance
};

// I_k^j for one row of C (ReprojectNeighbour's rules, in float, without branches): J = bilinear
// sample - 0.5 and mask 1 where valid, 0 elsewhere. The portable version; ReprojectRowAvx2
// below is the same 8 pixels at a time.
void ReprojectRow(const ReprojectionRow& p, const float* __restrict inv_z,
                  const float* __restrict shadow, const float* __restrict image,
                  float* __restrict J, float* __restrict mask, int n) {
  const float u_max = p.width - 0.5f, v_max = p.height - 0.5f;
  for (int col = 0; col < n; ++col) {
    const float z = 1.0f / inv_z[col];  // +inf where empty
    const float x = (p.ray0[0] + col * p.ray_dx[0]) * z + p.b[0];
    const float y = (p.ray0[1] + col * p.ray_dx[1]) * z + p.b[1];
    const float d = (p.ray0[2] + col * p.ray_dx[2]) * z + p.b[2];
    const float u = p.fx * x / d + p.cx, v = p.fy * y / d + p.cy;
    bool ok = inv_z[col] > 0 && d > 0 && u >= 0.5f && u <= u_max && v >= 0.5f && v <= v_max;
    const float uc = ok ? u : 0.5f, vc = ok ? v : 0.5f;  // safe to index with
    const int tu = std::min(static_cast<int>(uc), p.width - 1);
    const int tv = std::min(static_cast<int>(vc), p.height - 1);
    ok = ok && d * shadow[tv * p.width + tu] <= p.max_depth_ratio;
    const float sx = uc - 0.5f, sy = vc - 0.5f;
    const int x0 = std::min(static_cast<int>(sx), p.width - 1);
    const int y0 = std::min(static_cast<int>(sy), p.height - 1);
    const int x1 = std::min(x0 + 1, p.width - 1), y1 = std::min(y0 + 1, p.height - 1);
    const float fx = sx - x0, fy = sy - y0;
    const float a = image[y0 * p.width + x0], b = image[y0 * p.width + x1];
    const float c = image[y1 * p.width + x0], e = image[y1 * p.width + x1];
    const float top = a + fx * (b - a), bottom = c + fx * (e - c);
    J[col] = ok ? top + fy * (bottom - top) - 0.5f : 0.0f;
    mask[col] = ok ? 1.0f : 0.0f;
  }
}

#if MS_HAVE_AVX2_DISPATCH
// image[index[l]] and image[index[l] + 1] for 8 lanes: 4 + 4 gathers of 64-bit pairs, which cost
// half as much as 8 + 8 single floats.
__attribute__((target("avx2,fma"))) inline void GatherPairs(const float* image, __m256i index,
                                                            __m256* first, __m256* second) {
  const double* pairs = reinterpret_cast<const double*>(image);
  // The masked form with every lane on: the plain one trips GCC 12's uninitialised warning.
  const __m256d zero = _mm256_setzero_pd(), all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  const __m256 low = _mm256_castpd_ps(
      _mm256_mask_i32gather_pd(zero, pairs, _mm256_castsi256_si128(index), all, 4));
  const __m256 high = _mm256_castpd_ps(
      _mm256_mask_i32gather_pd(zero, pairs, _mm256_extracti128_si256(index, 1), all, 4));
  // low = a0 b0 a1 b1 | a2 b2 a3 b3, high = a4 b4 a5 b5 | a6 b6 a7 b7.
  const __m256 a =
      _mm256_shuffle_ps(low, high, _MM_SHUFFLE(2, 0, 2, 0));  // a0 a1 a4 a5 | a2 a3 a6 a7
  const __m256 b = _mm256_shuffle_ps(low, high, _MM_SHUFFLE(3, 1, 3, 1));
  *first = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(a), _MM_SHUFFLE(3, 1, 2, 0)));
  *second = _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(b), _MM_SHUFFLE(3, 1, 2, 0)));
}

// Asks for the cache lines one row below the first and last lanes' pixels of a map.
__attribute__((target("avx2"))) inline void PrefetchRowBelow(const float* map, __m256i index,
                                                             int width, int last) {
  const __m256i below = _mm256_add_epi32(index, _mm256_set1_epi32(width));
  const int first_lane = std::min(_mm256_cvtsi256_si32(below), last);
  const int last_lane = std::min(_mm256_extract_epi32(below, 7), last);
  _mm_prefetch(reinterpret_cast<const char*>(map + first_lane), _MM_HINT_T0);
  _mm_prefetch(reinterpret_cast<const char*>(map + last_lane), _MM_HINT_T0);
}

// The same with AVX2 gathers, 8 pixels at a time; the remainder by ReprojectRow.
__attribute__((target("avx2,fma"))) void ReprojectRowAvx2(
    const ReprojectionRow& p, const float* __restrict inv_z, const float* __restrict shadow,
    const float* __restrict image, float* __restrict J, float* __restrict mask, int n) {
  const __m256 half = _mm256_set1_ps(0.5f), one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
  const __m256 u_max = _mm256_set1_ps(p.width - 0.5f), v_max = _mm256_set1_ps(p.height - 0.5f);
  const __m256i last_col = _mm256_set1_epi32(p.width - 1),
                last_row = _mm256_set1_epi32(p.height - 1);
  const __m256i last_pair = _mm256_set1_epi32(p.width - 2);
  const __m256i stride = _mm256_set1_epi32(p.width), one_i = _mm256_set1_epi32(1);
  const __m256 ratio = _mm256_set1_ps(p.max_depth_ratio);
  const __m256 iota = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7);
  const int last_image = p.width * p.height - 1;
  int col = 0;
  for (; col + 8 <= n; col += 8) {
    const __m256 c = _mm256_add_ps(_mm256_set1_ps(static_cast<float>(col)), iota);
    const __m256 iz = _mm256_loadu_ps(inv_z + col);
    const __m256 z = _mm256_div_ps(one, iz);
    const __m256 x =
        _mm256_fmadd_ps(_mm256_fmadd_ps(c, _mm256_set1_ps(p.ray_dx[0]), _mm256_set1_ps(p.ray0[0])),
                        z, _mm256_set1_ps(p.b[0]));
    const __m256 y =
        _mm256_fmadd_ps(_mm256_fmadd_ps(c, _mm256_set1_ps(p.ray_dx[1]), _mm256_set1_ps(p.ray0[1])),
                        z, _mm256_set1_ps(p.b[1]));
    const __m256 d =
        _mm256_fmadd_ps(_mm256_fmadd_ps(c, _mm256_set1_ps(p.ray_dx[2]), _mm256_set1_ps(p.ray0[2])),
                        z, _mm256_set1_ps(p.b[2]));
    const __m256 u = _mm256_add_ps(_mm256_div_ps(_mm256_mul_ps(_mm256_set1_ps(p.fx), x), d),
                                   _mm256_set1_ps(p.cx));
    const __m256 v = _mm256_add_ps(_mm256_div_ps(_mm256_mul_ps(_mm256_set1_ps(p.fy), y), d),
                                   _mm256_set1_ps(p.cy));
    __m256 ok =
        _mm256_and_ps(_mm256_cmp_ps(iz, zero, _CMP_GT_OQ), _mm256_cmp_ps(d, zero, _CMP_GT_OQ));
    ok = _mm256_and_ps(
        ok, _mm256_and_ps(_mm256_cmp_ps(u, half, _CMP_GE_OQ), _mm256_cmp_ps(u, u_max, _CMP_LE_OQ)));
    ok = _mm256_and_ps(
        ok, _mm256_and_ps(_mm256_cmp_ps(v, half, _CMP_GE_OQ), _mm256_cmp_ps(v, v_max, _CMP_LE_OQ)));
    const __m256 uc = _mm256_blendv_ps(half, u, ok), vc = _mm256_blendv_ps(half, v, ok);
    if (_mm256_testz_ps(ok, ok)) {  // no lane reads anything
      _mm256_storeu_ps(J + col, zero);
      _mm256_storeu_ps(mask + col, zero);
      continue;
    }
    const __m256i tu = _mm256_min_epi32(_mm256_cvttps_epi32(uc), last_col);
    const __m256i tv = _mm256_min_epi32(_mm256_cvttps_epi32(vc), last_row);
    const __m256i shadow_index = _mm256_add_epi32(_mm256_mullo_epi32(tv, stride), tu);
    const __m256 depth_ratio = _mm256_mul_ps(d, _mm256_i32gather_ps(shadow, shadow_index, 4));
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(depth_ratio, ratio, _CMP_LE_OQ));
    const __m256 sx = _mm256_sub_ps(uc, half), sy = _mm256_sub_ps(vc, half);
    const __m256i x0 = _mm256_min_epi32(_mm256_cvttps_epi32(sx), last_col);
    const __m256i y0 = _mm256_min_epi32(_mm256_cvttps_epi32(sy), last_row);
    const __m256i y1 = _mm256_min_epi32(_mm256_add_epi32(y0, one_i), last_row);
    const __m256 fx = _mm256_sub_ps(sx, _mm256_cvtepi32_ps(x0));
    const __m256 fy = _mm256_sub_ps(sy, _mm256_cvtepi32_ps(y0));
    // The two columns of each row as one pair from xl = min(x0, width - 2): x1 = xl + 1 always,
    // and x0 = xl + 1 at the last column (where fx = 0).
    const __m256i xl = _mm256_min_epi32(x0, last_pair);
    const __m256 at_last = _mm256_castsi256_ps(_mm256_cmpgt_epi32(x0, xl));
    const __m256i row0 = _mm256_mullo_epi32(y0, stride), row1 = _mm256_mullo_epi32(y1, stride);
    __m256 a, b, e, f;
    const __m256i pair_index = _mm256_add_epi32(row1, xl);
    GatherPairs(image, _mm256_add_epi32(row0, xl), &a, &b);
    GatherPairs(image, pair_index, &e, &f);
    // C's next row reads the neighbour's rows just below these (where the cameras are upright):
    // ask for them now. Without this the gathers wait on memory: the hardware prefetchers do not
    // foresee a path that crosses the neighbour's rows at a slant (measured: docs/design/sweep.md).
    PrefetchRowBelow(image, pair_index, p.width, last_image);
    PrefetchRowBelow(shadow, shadow_index, p.width, last_image);
    a = _mm256_blendv_ps(a, b, at_last);
    e = _mm256_blendv_ps(e, f, at_last);
    const __m256 top = _mm256_fmadd_ps(fx, _mm256_sub_ps(b, a), a);
    const __m256 bottom = _mm256_fmadd_ps(fx, _mm256_sub_ps(f, e), e);
    const __m256 value = _mm256_sub_ps(_mm256_fmadd_ps(fy, _mm256_sub_ps(bottom, top), top), half);
    _mm256_storeu_ps(J + col, _mm256_and_ps(value, ok));
    _mm256_storeu_ps(mask + col, _mm256_and_ps(one, ok));
  }
  if (col < n) {
    ReprojectionRow rest = p;
    for (int i = 0; i < 3; ++i) rest.ray0[i] += col * rest.ray_dx[i];
    ReprojectRow(rest, inv_z + col, shadow, image, J + col, mask + col, n - col);
  }
}

#endif  // MS_HAVE_AVX2_DISPATCH

void ReprojectThrough(const SpanRasterizer& camera, const View& c, const View& n,
                      const cv::Mat& image, const SpanRasterizer& shadow,
                      double occlusion_tolerance, float* J, float* mask) {
  const Eigen::Matrix3d A = n.R * c.R.transpose();
  const Eigen::Vector3d b = n.t - A * c.t;
  const Intrinsics& kc = c.intrinsics;
  ReprojectionRow p;
  for (int i = 0; i < 3; ++i) {
    p.ray_dx[i] = static_cast<float>(A(i, 0) / kc.fx);
    p.b[i] = static_cast<float>(b[i]);
  }
  p.fx = static_cast<float>(n.intrinsics.fx);
  p.fy = static_cast<float>(n.intrinsics.fy);
  p.cx = static_cast<float>(n.intrinsics.cx);
  p.cy = static_cast<float>(n.intrinsics.cy);
  p.width = image.cols;
  p.height = image.rows;
  p.max_depth_ratio = static_cast<float>(1 + occlusion_tolerance);
  const int width = camera.width();
  CV_Assert(image.isContinuous());
#if MS_HAVE_AVX2_DISPATCH
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  const auto reproject_row = avx2 && image.cols >= 2 ? ReprojectRowAvx2 : ReprojectRow;
#else
  const auto reproject_row = ReprojectRow;
#endif
  for (int row = 0; row < camera.height(); ++row) {
    const Eigen::Vector3d ray0 =
        A * Eigen::Vector3d((0.5 - kc.cx) / kc.fx, (row + 0.5 - kc.cy) / kc.fy, 1.0);
    for (int i = 0; i < 3; ++i) p.ray0[i] = static_cast<float>(ray0[i]);
    const size_t offset = static_cast<size_t>(row) * width;
    reproject_row(p, camera.inverse_depth().data() + offset, shadow.inverse_depth().data(),
                  image.ptr<float>(), J + offset, mask + offset, width);
  }
}

}  // namespace

CpuSweepSlab::CpuSweepSlab(const SweepJob& job, const PreparedSweep& prep)
    : job_(job),
      prep_(prep),
      normals_(FaceNormals(job.mesh)),
      camera_raster_(prep.camera.view, prep.near, /*keep_face=*/true),
      ncc_(prep.camera.view.intrinsics.width, prep.camera.view.intrinsics.height,
           job.options.gaussian_sigma_px, job.options.min_texture_variance,
           job.options.min_window_weight) {
  for (const SweepCamera& n : prep.neighbours) shadow_maps_.emplace_back(n.view, prep.near, false);
  ncc_.SetCamera(prep.camera.image);
  const size_t pixels = camera_raster_.face().size();
  J_.resize(pixels);
  mask_.resize(pixels);
}

void CpuSweepSlab::Render(int k) {
  const auto soup = SweepFacets(job_.mesh, normals_, prep_.camera.view.Center(), prep_.alpha * k);
  camera_raster_.DrawSoup(soup);
  for (auto& s : shadow_maps_) s.DrawSoup(soup);
}

int64_t CpuSweepSlab::CoveredPixels() const {
  int64_t covered = 0;
  for (int32_t f : camera_raster_.face()) covered += f >= 0;
  return covered;
}

void CpuSweepSlab::Reproject(int j) {
  ReprojectThrough(camera_raster_, prep_.camera.view, prep_.neighbours[j].view,
                   prep_.neighbours[j].image, shadow_maps_[j], job_.options.occlusion_tolerance,
                   J_.data(), mask_.data());
}

int64_t CpuSweepSlab::Ncc(float* out) { return ncc_.Run(J_.data(), mask_.data(), out); }

namespace {

// What one thread finds over its share of the offsets.
struct ChunkResult {
  std::vector<TileWinner> best;
  int64_t covered_pixels = 0, valid_hypotheses = 0;
  double raster_s = 0, reproject_s = 0, ncc_s = 0, reduce_s = 0;
};

// One NCC map per neighbour, C's image size.
struct NccMaps {
  explicit NccMaps(const PreparedSweep& prep) : maps(prep.neighbours.size()) {
    const Intrinsics& k = prep.camera.view.intrinsics;
    for (LargeBuffer<float>& m : maps) {
      m.resize(static_cast<size_t>(k.width) * k.height);
      pointers.push_back(m.data());
    }
  }
  std::vector<LargeBuffer<float>> maps;
  std::vector<const float*> pointers;
};

// Offset k's mesh rendered from C and every neighbour's NCC against C into *maps.
void SweepOffset(int k, CpuSweepSlab* slab, NccMaps* maps, ChunkResult* out) {
  Timer stage;
  slab->Render(k);
  out->covered_pixels += slab->CoveredPixels();
  out->raster_s += stage.Seconds();
  for (size_t j = 0; j < maps->maps.size(); ++j) {
    stage.Restart();
    slab->Reproject(static_cast<int>(j));
    out->reproject_s += stage.Seconds();
    stage.Restart();
    out->valid_hypotheses += slab->Ncc(maps->maps[j].data());
    out->ncc_s += stage.Seconds();
  }
}

// Sweeps the offsets of `competing` taken one at a time from `next` (shared by the threads)
// until none is left. A thread's offsets ascend, so its winners keep UpdateTileWinners' ties.
ChunkResult SweepOffsets(const SweepJob& job, const PreparedSweep& prep, const WinnerRule& rule,
                         const std::vector<int>& competing,
                         const std::vector<const float*>& surface, std::atomic<int>* next) {
  const int num_offsets = static_cast<int>(competing.size());
  ChunkResult out;
  out.best.resize(prep.tiles.NumTiles());
  int i = next->fetch_add(1);
  if (i >= num_offsets) return out;  // a thread that started late: no buffers to set up
  CpuSweepSlab slab(job, prep);
  NccMaps maps(prep);
  for (; i < num_offsets; i = next->fetch_add(1)) {
    const int k = competing[i];
    SweepOffset(k, &slab, &maps, &out);
    Timer stage;
    UpdateTileWinners(prep.tiles, k, maps.pointers, surface, slab.faces().data(), nullptr, rule,
                      &out.best);
    out.reduce_s += stage.Seconds();
  }
  return out;
}

// Where C's ray through the winner's pixel centre meets the plane of its swept facet.
Eigen::Vector3d WinnerPosition(const TileWinner& w, const SweepJob& job, const PreparedSweep& prep,
                               const std::vector<Eigen::Vector3d>& normals) {
  const View& view = prep.camera.view;
  const Eigen::Vector3d center = view.Center();
  std::array<Eigen::Vector3d, 3> v;
  for (int i = 0; i < 3; ++i) {
    v[i] = SweepVertex(job.mesh.vertices[job.mesh.faces[w.face][i]], normals[w.face], center,
                       prep.alpha * w.offset);
  }
  return PixelRayOnFacet(view, Eigen::Vector2d(w.col + 0.5, w.row + 0.5), v, prep.near);
}

}  // namespace

Eigen::Vector3d PixelRayOnFacet(const View& view, const Eigen::Vector2d& pixel,
                                const std::array<Eigen::Vector3d, 3>& facet, double near) {
  const Eigen::Vector3d center = view.Center();
  const Eigen::Vector3d n = (facet[1] - facet[0]).cross(facet[2] - facet[0]);
  const Eigen::Vector3d ray = view.PixelRay(pixel);
  double s = n.dot(facet[0] - center) / n.dot(ray);
  // Camera z along the ray is s * ray_z: s's range for the facet's depths.
  const double ray_z = (view.R * ray).z();
  double z_min = INFINITY, z_max = -INFINITY;
  for (const Eigen::Vector3d& v : facet) {
    const double z = view.ToCamera(v).z();
    z_min = std::min(z_min, z);
    z_max = std::max(z_max, z);
  }
  z_min = std::max(z_min, near);
  if (ray_z > 0 && z_max >= z_min) {
    // Within rounding of the range the crossing stays as computed (results do not move).
    const double slack = 1e-9 * std::max(std::abs(z_min), std::abs(z_max));
    const double z = s * ray_z;
    if (!std::isfinite(s)) {
      s = 0.5 * (z_min + z_max) / ray_z;
    } else if (z < z_min - slack || z > z_max + slack) {
      s = std::clamp(z, z_min, z_max) / ray_z;
    }
  }
  return center + s * ray;
}

SweepResult CpuSweepKernel::Run(const SweepJob& job) {
  Timer total;
  const PreparedSweep prep = PrepareSweep(job);
  SweepResult result;
  result.stats = PreparedSweepStats(prep);
  SweepStats& stats = result.stats;
  const std::vector<Eigen::Vector3d> normals = FaceNormals(job.mesh);
  const WinnerRule rule = WinnerRule::For(job.options, static_cast<int>(prep.neighbours.size()));
  const std::vector<int> competing = CompetingOffsets(prep, rule);
  stats.prepare_s = total.Seconds();
  // The unswept mesh's NCC first, when the others must beat it (one thread: a nineteenth of the
  // work, and every other offset needs it).
  std::vector<ChunkResult> found(1);
  std::unique_ptr<NccMaps> surface_maps;
  std::vector<const float*> surface;
  if (rule.must_move) {
    CpuSweepSlab slab(job, prep);
    surface_maps = std::make_unique<NccMaps>(prep);
    SweepOffset(0, &slab, surface_maps.get(), &found[0]);
    surface = surface_maps->pointers;
  }
  // Each thread takes the next offset when it is done with one, so that the threads finish
  // together whatever each offset costs; the merge below keeps one thread's winners.
  const int num_offsets = static_cast<int>(competing.size());
  const int threads = std::clamp(cv::getNumThreads(), 1, std::max(1, num_offsets));
  std::atomic<int> next{0};
  found.resize(1 + threads);
  cv::parallel_for_(
      cv::Range(0, threads),
      [&](const cv::Range& range) {
        for (int c = range.start; c < range.end; ++c) {
          found[1 + c] = SweepOffsets(job, prep, rule, competing, surface, &next);
        }
      },
      threads);
  std::vector<TileWinner> best(prep.tiles.NumTiles());
  for (const ChunkResult& chunk : found) {
    for (size_t t = 0; t < chunk.best.size(); ++t) {
      if (BeatsInSweepOrder(chunk.best[t], best[t])) best[t] = chunk.best[t];
    }
    stats.covered_pixels += chunk.covered_pixels;
    stats.valid_hypotheses += chunk.valid_hypotheses;
    stats.raster_s += chunk.raster_s;
    stats.reproject_s += chunk.reproject_s;
    stats.ncc_s += chunk.ncc_s;
    stats.reduce_s += chunk.reduce_s;
  }
  for (TileWinner& tile : best) {
    if (tile.neighbour < 0) continue;
    tile.position = WinnerPosition(tile, job, prep, normals);
    result.points.push_back(MakeSweepPoint(tile, prep));
  }
  stats.total_s = total.Seconds();
  return result;
}

}  // namespace ms
