// The fast CPU kernel of the photometric gradient (photometric_gradient.h). Where a profile of
// the reference shows its time going (its rasteriser, page faults on its per-pair double maps
// and per-pixel world points, OpenCV's double filters; docs/design/refine.md), this kernel draws
// with the sweep's span rasteriser, keeps no per-pixel point (each pixel's point is recomputed from
// its ray and its face's plane), filters float maps, reuses its buffers pair after pair (pooled,
// not thread_local: workers use a thread per job), and sums the chain rule per face first, so the
// vertex arrays are touched once per face instead of three times per pixel.
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "refine/pair_sampling.h"
#include "refine/photometric_gradient.h"
#include "sweep/span_raster.h"

namespace ms {
namespace {

// A face seen from the reference camera centre C: the point of a pixel's unit ray r on the
// face's plane is C + d r with d = offset / (unit . r); its barycentric weights are
// phi0 = (x - p1) . g0, phi1 = (x - p2) . g1, phi2 = 1 - phi0 - phi1 (the reference's formulas
// with the triple products rearranged: g0 = n x (p2 - p1) / |n|^2, g1 = n x (p0 - p2) / |n|^2).
struct FacePlane {
  Eigen::Vector3d unit = Eigen::Vector3d::Zero();
  double offset = 0;
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d g0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d g1 = Eigen::Vector3d::Zero();
};

// What a face's pixels add to its three vertices (sums over the pixels, in pixel order).
struct FaceSums {
  std::array<double, 3> gradient{};  // sum of dE/dd phi_k / cos, along the face's unit normal
  std::array<double, 3> parallax{};  // sum of phi_k |d(neighbour pixel)/dd|^2 / cos^2
  std::array<double, 3> weight{};    // sum of phi_k
};

// The buffers of one thread, kept between pairs (same-sized pairs allocate nothing).
struct Workspace {
  std::optional<SpanRasterizer> seen, shadow;
  std::vector<std::array<Eigen::Vector3d, 3>> soup;
  std::vector<FacePlane> planes;
  std::vector<FaceSums> sums;
  std::vector<int32_t> face;  // the face a sampled pixel sees, -1 where the mask is 0
  // Float maps of the reference's size: the window's six inputs and their filtered sums; the
  // inputs are reused for the gradient's four coefficient maps, the sums for theirs filtered.
  std::array<cv::Mat, 6> in, sum;
  cv::Mat reprojected, dj_dd, parallax2;
};

// Workspaces outlive the threads that use them (a worker computes every job on a fresh
// thread): fresh buffers cost a page fault per 4 KiB, which made a worker's job several times
// slower than the same pair in `manisweep refine`. At most one per thread computing at once.
class WorkspacePool {
 public:
  class Lease {
   public:
    Lease(WorkspacePool* pool, std::unique_ptr<Workspace> ws) : pool_(pool), ws_(std::move(ws)) {}
    ~Lease() { pool_->Return(std::move(ws_)); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Workspace& operator*() const { return *ws_; }

   private:
    WorkspacePool* pool_;
    std::unique_ptr<Workspace> ws_;
  };

  Lease Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (free_.empty()) return Lease(this, std::make_unique<Workspace>());
    std::unique_ptr<Workspace> ws = std::move(free_.back());
    free_.pop_back();
    return Lease(this, std::move(ws));
  }

 private:
  void Return(std::unique_ptr<Workspace> ws) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(ws));
  }
  std::mutex mutex_;
  std::vector<std::unique_ptr<Workspace>> free_;
};

WorkspacePool& Workspaces() {
  static WorkspacePool* pool = new WorkspacePool();  // never destroyed: no exit-order trouble
  return *pool;
}

SpanRasterizer& Target(std::optional<SpanRasterizer>* raster, const View& view, double near,
                       bool keep_face) {
  if (raster->has_value()) {
    (*raster)->SetView(view, near);
  } else {
    raster->emplace(view, near, keep_face);
  }
  return **raster;
}

void PlanFaces(const Mesh& mesh, const Eigen::Vector3d& centre, Workspace* ws) {
  ws->soup.resize(mesh.faces.size());
  ws->planes.resize(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3d& p0 = mesh.vertices[t[0]];
    const Eigen::Vector3d& p1 = mesh.vertices[t[1]];
    const Eigen::Vector3d& p2 = mesh.vertices[t[2]];
    ws->soup[f] = {p0, p1, p2};
    FacePlane& plane = ws->planes[f];
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    const double n2 = n.squaredNorm();
    if (!(n2 > 0)) {  // no area: it covers no pixel, and its plane is left at zero
      plane = FacePlane();
      continue;
    }
    plane.unit = n / std::sqrt(n2);
    plane.offset = plane.unit.dot(p0 - centre);
    plane.p1 = p1;
    plane.p2 = p2;
    plane.g0 = n.cross(p2 - p1) / n2;
    plane.g1 = n.cross(p0 - p2) / n2;
  }
}

// Samples the neighbour through the mesh for every pixel of the reference (the reference
// kernel's SamplePixels): fills ws->face, the window's six inputs m, mI, mJ, mI^2, mJ^2, mIJ,
// and J, dJ/dd and the squared parallax rate where the mask is 1.
void SamplePixels(const Mesh& mesh, const RefineView& reference, const RefineView& neighbour,
                  const RefineOptions& options, Workspace* ws) {
  const View& vi = reference.view;
  const View& vj = neighbour.view;
  const Intrinsics& kj = vj.intrinsics;
  const int w = vi.intrinsics.width, h = vi.intrinsics.height;
  const double near_j = RefineNearPlane(mesh, vj);
  SpanRasterizer& seen = Target(&ws->seen, vi, RefineNearPlane(mesh, vi), true);
  SpanRasterizer& shadow = Target(&ws->shadow, vj, near_j, false);
  seen.DrawSoup(ws->soup);
  shadow.DrawSoup(ws->soup);

  for (cv::Mat& m : ws->in) m.create(h, w, CV_32F);
  ws->reprojected.create(h, w, CV_32F);
  ws->dj_dd.create(h, w, CV_32F);
  ws->parallax2.create(h, w, CV_32F);
  ws->face.assign(static_cast<size_t>(w) * h, -1);
  const PixelRays rays(vi);
  const Eigen::Vector3d centre_j = vj.ToCamera(vi.Center());  // C_i in camera j
  const double max_depth_ratio = 1 + options.occlusion_tolerance;
  const float* shadow_inv_z = shadow.inverse_depth().data();
  for (int row = 0; row < h; ++row) {
    const int32_t* seen_face = seen.face().data() + static_cast<size_t>(row) * w;
    int32_t* face = ws->face.data() + static_cast<size_t>(row) * w;
    const double* image_i = reference.image.ptr<double>(row);
    float* m = ws->in[0].ptr<float>(row);
    float* mi = ws->in[1].ptr<float>(row);
    float* mj = ws->in[2].ptr<float>(row);
    float* mii = ws->in[3].ptr<float>(row);
    float* mjj = ws->in[4].ptr<float>(row);
    float* mij = ws->in[5].ptr<float>(row);
    float* J = ws->reprojected.ptr<float>(row);
    float* dj_dd = ws->dj_dd.ptr<float>(row);
    float* parallax2 = ws->parallax2.ptr<float>(row);
    for (int col = 0; col < w; ++col) {
      m[col] = mi[col] = mj[col] = mii[col] = mjj[col] = mij[col] = 0;
      const int32_t f = seen_face[col];
      if (f < 0) continue;
      const FacePlane& plane = ws->planes[f];
      const Eigen::Vector3d ray = rays(col, row);
      const double cos = plane.unit.dot(ray);
      if (std::abs(cos) < options.min_cos_incidence || cos == 0) continue;
      const double depth = plane.offset / cos;
      const Eigen::Vector3d ray_j = vj.R * ray;  // d(camera-j coordinates)/dd
      const Eigen::Vector3d y = centre_j + depth * ray_j;
      const std::optional<NeighbourPixel> q = ProjectToNeighbour(kj, y, near_j);
      if (!q) continue;
      // 1/z is 0 where the neighbour sees nothing: that passes, as the reference's infinity.
      if (y.z() * shadow_inv_z[static_cast<size_t>(q->row) * kj.width + q->col] > max_depth_ratio) {
        continue;  // something nearer hides the point from the neighbour
      }
      const BilinearSample s = SampleBilinear(neighbour.image, q->ax, q->ay);
      const Eigen::Vector2d rate = ProjectionRate(kj, y, ray_j);
      const double du = rate.x(), dv = rate.y();
      const double i = image_i[col], j = s.value;
      face[col] = f;
      m[col] = 1;
      mi[col] = static_cast<float>(i);
      mj[col] = static_cast<float>(j);
      mii[col] = static_cast<float>(i * i);
      mjj[col] = static_cast<float>(j * j);
      mij[col] = static_cast<float>(i * j);
      J[col] = static_cast<float>(j);
      dj_dd[col] = static_cast<float>(s.dx * du + s.dy * dv);
      parallax2[col] = static_cast<float>(du * du + dv * dv);
    }
  }
}

// The Gaussian window of the reference (radius ceil(3 sigma), zero outside the image) in float.
class FloatGaussianWindow {
 public:
  explicit FloatGaussianWindow(double sigma) {
    const int radius = static_cast<int>(std::ceil(3 * sigma));
    kernel_ = cv::getGaussianKernel(2 * radius + 1, sigma, CV_32F);
  }
  void operator()(const cv::Mat& in, cv::Mat* out) const {
    cv::sepFilter2D(in, *out, CV_32F, kernel_, kernel_, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
  }

 private:
  cv::Mat kernel_;
};

}  // namespace

PairGradient ComputePairGradientFast(const Mesh& mesh, const RefineView& reference,
                                     const RefineView& neighbour, const RefineOptions& options) {
  const WorkspacePool::Lease lease = Workspaces().Take();
  Workspace& ws = *lease;
  const View& vi = reference.view;
  const Eigen::Vector3d centre = vi.Center();
  PlanFaces(mesh, centre, &ws);
  SamplePixels(mesh, reference, neighbour, options, &ws);
  const FloatGaussianWindow window(options.gaussian_sigma_px);
  for (size_t k = 0; k < ws.in.size(); ++k) window(ws.in[k], &ws.sum[k]);

  // Per defined pixel, the coefficients of dZNCC_p/dJ(q) as the reference's:
  //   a = 1 / (S_m sqrt(var_I var_J)), a mu_I, b = ZNCC / (S_m var_J), b mu_J,
  // written over the window's inputs mI..mJ^2 (no longer needed; m stays for the test below).
  PairGradient out;
  out.Resize(mesh.vertices.size());
  const int h = reference.image.rows, w = reference.image.cols;
  cv::Mat& a = ws.in[1];
  cv::Mat& a_mu = ws.in[2];
  cv::Mat& b = ws.in[3];
  cv::Mat& b_mu = ws.in[4];
  for (int row = 0; row < h; ++row) {
    const float* m = ws.in[0].ptr<float>(row);
    const float* sm = ws.sum[0].ptr<float>(row);
    const float* si = ws.sum[1].ptr<float>(row);
    const float* sj = ws.sum[2].ptr<float>(row);
    const float* sii = ws.sum[3].ptr<float>(row);
    const float* sjj = ws.sum[4].ptr<float>(row);
    const float* sij = ws.sum[5].ptr<float>(row);
    float* a_row = a.ptr<float>(row);
    float* a_mu_row = a_mu.ptr<float>(row);
    float* b_row = b.ptr<float>(row);
    float* b_mu_row = b_mu.ptr<float>(row);
    for (int col = 0; col < w; ++col) {
      a_row[col] = a_mu_row[col] = b_row[col] = b_mu_row[col] = 0;
      const double weight = sm[col];
      if (m[col] == 0 || weight < 0.5) continue;  // half the window at least
      const double mu_i = si[col] / weight, mu_j = sj[col] / weight;
      const double var_i = sii[col] / weight - mu_i * mu_i;
      const double var_j = sjj[col] / weight - mu_j * mu_j;
      if (var_i < options.min_texture_variance || var_j < options.min_texture_variance) continue;
      const double cov = sij[col] / weight - mu_i * mu_j;
      const double root = std::sqrt(var_i * var_j);
      const double ncc = cov / root;
      out.energy += 1 - ncc;
      ++out.pixels;
      a_row[col] = static_cast<float>(1 / (weight * root));
      a_mu_row[col] = static_cast<float>(mu_i / (weight * root));
      b_row[col] = static_cast<float>(ncc / (weight * var_j));
      b_mu_row[col] = static_cast<float>(ncc * mu_j / (weight * var_j));
    }
  }
  cv::Mat& ga = ws.sum[1];
  cv::Mat& ga_mu = ws.sum[2];
  cv::Mat& gb = ws.sum[3];
  cv::Mat& gb_mu = ws.sum[4];
  window(a, &ga);
  window(a_mu, &ga_mu);
  window(b, &gb);
  window(b_mu, &gb_mu);

  // The chain rule (docs/design/refine.md), summed per face in pixel order, then per vertex in face
  // order: dE/dv_k = sum_p dE/dd(p) phi_k(p) unit / cos(p).
  ws.sums.assign(mesh.faces.size(), FaceSums());
  const PixelRays rays(vi);
  for (int row = 0; row < h; ++row) {
    const int32_t* face = ws.face.data() + static_cast<size_t>(row) * w;
    const double* image_i = reference.image.ptr<double>(row);
    const float* J = ws.reprojected.ptr<float>(row);
    const float* dj_dd = ws.dj_dd.ptr<float>(row);
    const float* parallax2 = ws.parallax2.ptr<float>(row);
    const float* ga_row = ga.ptr<float>(row);
    const float* ga_mu_row = ga_mu.ptr<float>(row);
    const float* gb_row = gb.ptr<float>(row);
    const float* gb_mu_row = gb_mu.ptr<float>(row);
    for (int col = 0; col < w; ++col) {
      const int32_t f = face[col];
      if (f < 0) continue;
      const double dncc_dj = image_i[col] * ga_row[col] - ga_mu_row[col] -
                             static_cast<double>(J[col]) * gb_row[col] + gb_mu_row[col];
      const double de_dd = -dncc_dj * dj_dd[col];
      const FacePlane& plane = ws.planes[f];
      const Eigen::Vector3d ray = rays(col, row);
      const double cos = plane.unit.dot(ray);
      const Eigen::Vector3d x = centre + (plane.offset / cos) * ray;
      const double phi0 = (x - plane.p1).dot(plane.g0);
      const double phi1 = (x - plane.p2).dot(plane.g1);
      const std::array<double, 3> phi = BarycentricOnFace(phi0, phi1);
      const double per_phi_gradient = de_dd / cos;
      const double per_phi_parallax = parallax2[col] / (cos * cos);
      FaceSums& s = ws.sums[f];
      for (int k = 0; k < 3; ++k) {
        s.gradient[k] += per_phi_gradient * phi[k];
        s.parallax[k] += per_phi_parallax * phi[k];
        s.weight[k] += phi[k];
      }
    }
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const FaceSums& s = ws.sums[f];
    const auto& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      out.gradient[t[k]] += s.gradient[k] * ws.planes[f].unit;
      out.parallax_rate2[t[k]] += s.parallax[k];
      out.weight[t[k]] += s.weight[k];
    }
  }
  return out;
}

}  // namespace ms
