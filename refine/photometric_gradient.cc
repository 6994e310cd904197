#include "refine/photometric_gradient.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "refine/pair_sampling.h"
#include "sweep/software_raster.h"

namespace ms {
namespace {

// The Gaussian window as a separable filter with zero outside the image, so that filtering is
// the same sum in both directions (the gradient's second filtering is the first's adjoint).
class GaussianWindow {
 public:
  explicit GaussianWindow(double sigma) {
    const int radius = static_cast<int>(std::ceil(3 * sigma));
    kernel_ = cv::getGaussianKernel(2 * radius + 1, sigma, CV_64F);
  }
  cv::Mat operator()(const cv::Mat& in) const {
    cv::Mat out;
    cv::sepFilter2D(in, out, CV_64F, kernel_, kernel_, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
    return out;
  }

 private:
  cv::Mat kernel_;
};

// What the reference's pixel sees through the mesh, for the pixels where the neighbour's image
// is defined (mask 1).
struct PixelSamples {
  cv::Mat mask, reference, reprojected;  // m, I, J (CV_64F)
  std::vector<double> dj_dd;             // dJ/dd along the unit ray
  std::vector<double> parallax2;         // |d(neighbour pixel)/dd|^2
  std::vector<int32_t> face;             // -1 where masked out
  std::vector<Eigen::Vector3d> world;
  std::vector<Eigen::Vector3d> ray;
};

PixelSamples SamplePixels(const Mesh& mesh, const RefineView& reference,
                          const RefineView& neighbour, const RefineOptions& options) {
  const Intrinsics& ki = reference.view.intrinsics;
  const Intrinsics& kj = neighbour.view.intrinsics;
  SoftwareRasterizer seen(reference.view, RefineNearPlane(mesh, reference.view), true);
  const double near_j = RefineNearPlane(mesh, neighbour.view);
  SoftwareRasterizer shadow(neighbour.view, near_j, false);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    seen.DrawTriangle(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]],
                      static_cast<int32_t>(f));
    shadow.DrawTriangle(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]],
                        static_cast<int32_t>(f));
  }
  const int w = ki.width, h = ki.height;
  PixelSamples s;
  s.mask = cv::Mat::zeros(h, w, CV_64F);
  s.reference = reference.image;
  s.reprojected = cv::Mat::zeros(h, w, CV_64F);
  s.dj_dd.assign(static_cast<size_t>(w) * h, 0);
  s.parallax2.assign(s.dj_dd.size(), 0);
  s.face.assign(s.dj_dd.size(), -1);
  s.world.assign(s.dj_dd.size(), Eigen::Vector3d::Zero());
  s.ray.assign(s.dj_dd.size(), Eigen::Vector3d::Zero());
  const PixelRays rays(reference.view);
  const Eigen::Matrix3d& rj = neighbour.view.R;
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const size_t p = seen.Index(col, row);
      const int32_t f = seen.face()[p];
      if (f < 0) continue;
      const Eigen::Vector3d ray = rays(col, row);
      const Eigen::Vector3d normal = mesh.FaceNormal(f);
      if (std::abs(normal.dot(ray)) < options.min_cos_incidence) continue;
      const Eigen::Vector3d& x = seen.world()[p];
      const Eigen::Vector3d y = neighbour.view.ToCamera(x);
      const std::optional<NeighbourPixel> q = ProjectToNeighbour(kj, y, near_j);
      if (!q) continue;
      if (y.z() >
          shadow.depth()[shadow.Index(q->col, q->row)] * (1 + options.occlusion_tolerance)) {
        continue;  // something nearer hides the point from the neighbour
      }
      const BilinearSample j = SampleBilinear(neighbour.image, q->ax, q->ay);
      const Eigen::Vector2d rate = ProjectionRate(kj, y, rj * ray);
      const double du = rate.x(), dv = rate.y();
      s.mask.at<double>(row, col) = 1;
      s.reprojected.at<double>(row, col) = j.value;
      s.dj_dd[p] = j.dx * du + j.dy * dv;
      s.parallax2[p] = du * du + dv * dv;
      s.face[p] = f;
      s.world[p] = x;
      s.ray[p] = ray;
    }
  }
  return s;
}

}  // namespace

void PairGradient::Resize(size_t vertices) {
  gradient.assign(vertices, Eigen::Vector3d::Zero());
  parallax_rate2.assign(vertices, 0);
  weight.assign(vertices, 0);
}

void PairGradient::Add(const PairGradient& other) {
  energy += other.energy;
  pixels += other.pixels;
  if (gradient.size() != other.gradient.size()) Resize(other.gradient.size());
  for (size_t v = 0; v < gradient.size(); ++v) {
    gradient[v] += other.gradient[v];
    parallax_rate2[v] += other.parallax_rate2[v];
    weight[v] += other.weight[v];
  }
}

PairGradient ComputePairGradientReference(const Mesh& mesh, const RefineView& reference,
                                          const RefineView& neighbour,
                                          const RefineOptions& options) {
  PairGradient out;
  out.Resize(mesh.vertices.size());
  const PixelSamples s = SamplePixels(mesh, reference, neighbour, options);
  const cv::Mat& m = s.mask;
  const cv::Mat& I = s.reference;
  const cv::Mat& J = s.reprojected;
  const GaussianWindow window(options.gaussian_sigma_px);
  const cv::Mat mi = m.mul(I), mj = m.mul(J);
  const cv::Mat sm = window(m), si = window(mi), sj = window(mj);
  const cv::Mat sii = window(mi.mul(I)), sjj = window(mj.mul(J)), sij = window(mi.mul(J));

  // Per defined pixel p, the coefficients of dZNCC_p/dJ(q) (docs/design/refine.md):
  //   G(p - q) m(q) [a(p) (I(q) - mu_I(p)) - b(p) (J(q) - mu_J(p))],
  // a = 1 / (S_m sqrt(var_I var_J)), b = ZNCC / (S_m var_J).
  const int h = m.rows, w = m.cols;
  cv::Mat a = cv::Mat::zeros(h, w, CV_64F), a_mu = a.clone(), b = a.clone(), b_mu = a.clone();
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const double weight = sm.at<double>(row, col);
      if (m.at<double>(row, col) == 0 || weight < 0.5) continue;  // half the window at least
      const double mu_i = si.at<double>(row, col) / weight;
      const double mu_j = sj.at<double>(row, col) / weight;
      const double var_i = sii.at<double>(row, col) / weight - mu_i * mu_i;
      const double var_j = sjj.at<double>(row, col) / weight - mu_j * mu_j;
      if (var_i < options.min_texture_variance || var_j < options.min_texture_variance) continue;
      const double cov = sij.at<double>(row, col) / weight - mu_i * mu_j;
      const double root = std::sqrt(var_i * var_j);
      const double ncc = cov / root;
      out.energy += 1 - ncc;
      ++out.pixels;
      a.at<double>(row, col) = 1 / (weight * root);
      a_mu.at<double>(row, col) = mu_i / (weight * root);
      b.at<double>(row, col) = ncc / (weight * var_j);
      b_mu.at<double>(row, col) = ncc * mu_j / (weight * var_j);
    }
  }
  const cv::Mat ga = window(a), ga_mu = window(a_mu), gb = window(b), gb_mu = window(b_mu);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const size_t q = static_cast<size_t>(row) * w + col;
      const int32_t f = s.face[q];
      if (f < 0) continue;
      const double dncc_dj =
          I.at<double>(row, col) * ga.at<double>(row, col) - ga_mu.at<double>(row, col) -
          J.at<double>(row, col) * gb.at<double>(row, col) + gb_mu.at<double>(row, col);
      const double de_dd = -dncc_dj * s.dj_dd[q];
      const auto& t = mesh.faces[f];
      const Eigen::Vector3d& p0 = mesh.vertices[t[0]];
      const Eigen::Vector3d& p1 = mesh.vertices[t[1]];
      const Eigen::Vector3d& p2 = mesh.vertices[t[2]];
      const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
      const double n2 = n.squaredNorm();
      const Eigen::Vector3d& x = s.world[q];
      const double phi0 = (p2 - p1).cross(x - p1).dot(n) / n2;
      const double phi1 = (p0 - p2).cross(x - p2).dot(n) / n2;
      const std::array<double, 3> phi = BarycentricOnFace(phi0, phi1);
      const Eigen::Vector3d unit = n / std::sqrt(n2);
      const double cos = unit.dot(s.ray[q]);
      const Eigen::Vector3d dd_dv = unit / cos;  // times phi_k: dd/dv_k
      for (int k = 0; k < 3; ++k) {
        const double weight = phi[k];
        out.gradient[t[k]] += (de_dd * weight) * dd_dv;
        out.parallax_rate2[t[k]] += weight * s.parallax2[q] / (cos * cos);
        out.weight[t[k]] += weight;
      }
    }
  }
  return out;
}

}  // namespace ms
