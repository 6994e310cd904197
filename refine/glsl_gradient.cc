#include "refine/glsl_gradient.h"

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "gl/gl_api.h"
#include "gl/mesh_renderer.h"
#include "gl/objects.h"
#include "refine/pair_sampling.h"

namespace ms {
namespace {

constexpr int kGroupX = 16, kGroupY = 8;  // the local size of every refine_*.comp

// One face as refine_faces.glsl reads it (std430: five vec4).
struct GpuFace {
  std::array<float, 4> unit_offset, p1, p2, g0, g1;
};

std::array<float, 4> Vec4(const Eigen::Vector3d& v, double w = 0) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z()),
          static_cast<float>(w)};
}

// The faces' planes and barycentric gradients relative to `centre` (photometric_gradient_fast.cc
// PlanFaces, in float for the GPU); a face without area is left zero and covers nothing.
std::vector<GpuFace> PlanFaces(const Mesh& mesh, const Eigen::Vector3d& centre) {
  std::vector<GpuFace> faces(mesh.faces.size(), GpuFace{});
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3d p0 = mesh.vertices[t[0]] - centre;
    const Eigen::Vector3d p1 = mesh.vertices[t[1]] - centre;
    const Eigen::Vector3d p2 = mesh.vertices[t[2]] - centre;
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    const double n2 = n.squaredNorm();
    if (!(n2 > 0)) continue;
    const Eigen::Vector3d unit = n / std::sqrt(n2);
    faces[f] = {Vec4(unit, unit.dot(p0)), Vec4(p1), Vec4(p2), Vec4(n.cross(p2 - p1) / n2),
                Vec4(n.cross(p0 - p2) / n2)};
  }
  return faces;
}

Eigen::Vector4f Intrinsics4(const Intrinsics& k) {
  return Eigen::Vector4d(k.fx, k.fy, k.cx, k.cy).cast<float>();
}

}  // namespace

struct GlslPairGradient::Impl {
  std::unique_ptr<gl::GlContext> context;
  std::unique_ptr<gl::MeshRenderer> renderer;
  std::unique_ptr<gl::Framebuffer> seen, shadow;  // the reference's and the neighbour's renderings
  std::unique_ptr<gl::ShaderProgram> sample, blur, coefficients, chain;
  gl::Buffer faces, weights;
  double weights_sigma = -1;  // the window `weights` holds
  Mesh uploaded;              // the mesh the renderer holds (pairs of one round share it)

  // Maps of the reference's size.
  struct Maps {
    gl::Texture2D window0, window1, face, scratch, sums0, sums1, coefficients, filtered, energy,
        chain;
    Maps(int w, int h)
        : window0(w, h, gl::TextureFormat::kRGBA32F),
          window1(w, h, gl::TextureFormat::kRGBA32F),
          face(w, h, gl::TextureFormat::kR32I),
          scratch(w, h, gl::TextureFormat::kRGBA32F),
          sums0(w, h, gl::TextureFormat::kRGBA32F),
          sums1(w, h, gl::TextureFormat::kRGBA32F),
          coefficients(w, h, gl::TextureFormat::kRGBA32F),
          filtered(w, h, gl::TextureFormat::kRGBA32F),
          energy(w, h, gl::TextureFormat::kR32F),
          chain(w, h, gl::TextureFormat::kRGBA32F) {}
  };
  std::unique_ptr<Maps> maps;

  void UseMesh(const Mesh& mesh) {
    if (renderer && mesh.vertices == uploaded.vertices && mesh.faces == uploaded.faces) return;
    if (renderer) {
      renderer->SetMesh(mesh);
    } else {
      renderer = std::make_unique<gl::MeshRenderer>(*context, mesh);
    }
    uploaded = mesh;
  }

  // `in` filtered by the Gaussian window into `out`, rows then columns.
  void Blur(const gl::Texture2D& in, const gl::Texture2D& out, int radius) const {
    const Eigen::Vector2i size(in.width(), in.height());
    blur->Set("u_size", size);
    blur->Set("u_radius", radius);
    weights.BindStorage(1);
    const gl::Texture2D* from[2] = {&in, &maps->scratch};
    const gl::Texture2D* to[2] = {&maps->scratch, &out};
    for (int axis = 0; axis < 2; ++axis) {
      blur->Set("u_axis", axis);
      from[axis]->BindImage(0, gl::ImageAccess::kReadOnly);
      to[axis]->BindImage(1, gl::ImageAccess::kWriteOnly);
      blur->Dispatch(gl::DivideRoundingUp(size.x(), kGroupX),
                     gl::DivideRoundingUp(size.y(), kGroupY));
      gl::MemoryBarrier();
    }
  }

  PairGradient Compute(const Mesh& mesh, const RefineView& reference, const RefineView& neighbour,
                       const RefineOptions& options);
  // The passes of Compute, in order.
  void SampleNeighbour(const RefineView& reference, const RefineView& neighbour, double near_j,
                       const Eigen::Vector3d& centre, const RefineOptions& options);
  void ZnccCoefficients(const Eigen::Vector2i& size, const RefineOptions& options);
  void ChainRule(const View& vi, const Eigen::Vector2i& size);
  void SumPerVertex(const Mesh& mesh, int w, int h, PairGradient* out) const;
};

PairGradient GlslPairGradient::Impl::Compute(const Mesh& mesh, const RefineView& reference,
                                             const RefineView& neighbour,
                                             const RefineOptions& options) {
  PairGradient out;
  out.Resize(mesh.vertices.size());
  if (mesh.faces.empty()) return out;
  const View& vi = reference.view;
  const View& vj = neighbour.view;
  const int w = vi.intrinsics.width, h = vi.intrinsics.height;
  const Eigen::Vector3d centre = vi.Center();

  // The two renderings: the face each reference pixel sees, the neighbour's depth.
  UseMesh(mesh);
  gl::DepthRenderOptions render;
  render.near = RefineNearPlane(mesh, vi);
  if (!renderer->RenderTargets(vi, render, &seen)) return out;
  const double near_j = RefineNearPlane(mesh, vj);
  render.near = near_j;
  renderer->RenderTargets(vj, render, &shadow);
  gl::MemoryBarrier();

  if (!maps || maps->window0.width() != w || maps->window0.height() != h) {
    maps = std::make_unique<Maps>(w, h);
  }
  faces = gl::Buffer::FromVector(PlanFaces(mesh, centre));
  faces.BindStorage(0);
  SampleNeighbour(reference, neighbour, near_j, centre, options);
  ZnccCoefficients(Eigen::Vector2i(w, h), options);
  ChainRule(vi, Eigen::Vector2i(w, h));
  gl::CheckGlError("refine gradient passes");
  SumPerVertex(mesh, w, h, &out);
  return out;
}

// Pass 1: the neighbour through the mesh, into the windows' per-pixel values.
void GlslPairGradient::Impl::SampleNeighbour(const RefineView& reference,
                                             const RefineView& neighbour, double near_j,
                                             const Eigen::Vector3d& centre,
                                             const RefineOptions& options) {
  const View& vi = reference.view;
  const View& vj = neighbour.view;
  const int w = vi.intrinsics.width, h = vi.intrinsics.height;
  cv::Mat image_i, image_j;
  reference.image.convertTo(image_i, CV_32F);
  neighbour.image.convertTo(image_j, CV_32F);
  const gl::Texture2D texture_i = gl::Texture2D::FromImage(image_i, gl::TextureFormat::kR32F);
  const gl::Texture2D texture_j = gl::Texture2D::FromImage(image_j, gl::TextureFormat::kR32F);
  sample->Set("u_rt_i", Eigen::Matrix3f(vi.R.transpose().cast<float>()));
  sample->Set("u_k_i", Intrinsics4(vi.intrinsics));
  sample->Set("u_size_i", Eigen::Vector2i(w, h));
  sample->Set("u_size_j", Eigen::Vector2i(vj.intrinsics.width, vj.intrinsics.height));
  sample->Set("u_r_j", Eigen::Matrix3f(vj.R.cast<float>()));
  sample->Set("u_centre_j", Eigen::Vector3f(vj.ToCamera(centre).cast<float>()));
  sample->Set("u_k_j", Intrinsics4(vj.intrinsics));
  sample->Set("u_near_j", static_cast<float>(near_j));
  sample->Set("u_min_cos", static_cast<float>(options.min_cos_incidence));
  sample->Set("u_max_depth_ratio", static_cast<float>(1 + options.occlusion_tolerance));
  maps->window0.BindImage(0, gl::ImageAccess::kWriteOnly);
  maps->window1.BindImage(1, gl::ImageAccess::kWriteOnly);
  maps->face.BindImage(2, gl::ImageAccess::kWriteOnly);
  seen->color(2).BindImage(3, gl::ImageAccess::kReadOnly);
  shadow->color(0).BindImage(4, gl::ImageAccess::kReadOnly);
  texture_i.BindImage(5, gl::ImageAccess::kReadOnly);
  texture_j.BindImage(6, gl::ImageAccess::kReadOnly);
  sample->Dispatch(gl::DivideRoundingUp(w, kGroupX), gl::DivideRoundingUp(h, kGroupY));
  gl::MemoryBarrier();
}

// The window's sums (the fast CPU kernel's float Gaussian), then pass 2: ZNCC and its
// coefficients, filtered again.
void GlslPairGradient::Impl::ZnccCoefficients(const Eigen::Vector2i& size,
                                              const RefineOptions& options) {
  const int radius = static_cast<int>(std::ceil(3 * options.gaussian_sigma_px));
  if (weights_sigma != options.gaussian_sigma_px) {
    const cv::Mat kernel = cv::getGaussianKernel(2 * radius + 1, options.gaussian_sigma_px, CV_32F);
    weights =
        gl::Buffer::FromVector(std::vector<float>(kernel.begin<float>(), kernel.end<float>()));
    weights_sigma = options.gaussian_sigma_px;
  }
  Blur(maps->window0, maps->sums0, radius);
  Blur(maps->window1, maps->sums1, radius);
  coefficients->Set("u_size", size);
  coefficients->Set("u_min_variance", static_cast<float>(options.min_texture_variance));
  maps->window0.BindImage(0, gl::ImageAccess::kReadOnly);
  maps->sums0.BindImage(1, gl::ImageAccess::kReadOnly);
  maps->sums1.BindImage(2, gl::ImageAccess::kReadOnly);
  maps->coefficients.BindImage(3, gl::ImageAccess::kWriteOnly);
  maps->energy.BindImage(4, gl::ImageAccess::kWriteOnly);
  coefficients->Dispatch(gl::DivideRoundingUp(size.x(), kGroupX),
                         gl::DivideRoundingUp(size.y(), kGroupY));
  gl::MemoryBarrier();
  Blur(maps->coefficients, maps->filtered, radius);
}

// Pass 3: the chain rule per pixel.
void GlslPairGradient::Impl::ChainRule(const View& vi, const Eigen::Vector2i& size) {
  faces.BindStorage(0);
  chain->Set("u_rt_i", Eigen::Matrix3f(vi.R.transpose().cast<float>()));
  chain->Set("u_k_i", Intrinsics4(vi.intrinsics));
  chain->Set("u_size", size);
  maps->window0.BindImage(0, gl::ImageAccess::kReadOnly);
  maps->window1.BindImage(1, gl::ImageAccess::kReadOnly);
  maps->filtered.BindImage(2, gl::ImageAccess::kReadOnly);
  maps->face.BindImage(3, gl::ImageAccess::kReadOnly);
  maps->chain.BindImage(4, gl::ImageAccess::kWriteOnly);
  chain->Dispatch(gl::DivideRoundingUp(size.x(), kGroupX), gl::DivideRoundingUp(size.y(), kGroupY));
  gl::MemoryBarrier();
}

// Per face in pixel order, then per vertex in face order (photometric_gradient_fast.cc).
void GlslPairGradient::Impl::SumPerVertex(const Mesh& mesh, int w, int h, PairGradient* out) const {
  const cv::Mat face = maps->face.Download();
  const cv::Mat per_pixel = maps->chain.Download();
  const cv::Mat energy = maps->energy.Download();
  std::vector<std::array<double, 9>> sums(mesh.faces.size(), std::array<double, 9>{});
  for (int row = 0; row < h; ++row) {
    const int32_t* f_row = face.ptr<int32_t>(row);
    const cv::Vec4f* c_row = per_pixel.ptr<cv::Vec4f>(row);
    const float* e_row = energy.ptr<float>(row);
    for (int col = 0; col < w; ++col) {
      if (e_row[col] > -0.5f) {  // a defined ZNCC
        out->energy += e_row[col];
        ++out->pixels;
      }
      const int32_t f = f_row[col];
      if (f < 0) continue;
      const cv::Vec4f& c = c_row[col];
      const std::array<double, 3> phi = BarycentricOnFace(c[2], c[3]);
      std::array<double, 9>& s = sums[f];
      for (int k = 0; k < 3; ++k) {
        s[k] += c[0] * phi[k];
        s[3 + k] += c[1] * phi[k];
        s[6 + k] += phi[k];
      }
    }
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3d n = (mesh.vertices[t[1]] - mesh.vertices[t[0]])
                                  .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    if (!(n.squaredNorm() > 0)) continue;  // no area: no pixel sees it
    const Eigen::Vector3d unit = n.normalized();
    for (int k = 0; k < 3; ++k) {
      out->gradient[t[k]] += sums[f][k] * unit;
      out->parallax_rate2[t[k]] += sums[f][3 + k];
      out->weight[t[k]] += sums[f][6 + k];
    }
  }
}

GlslPairGradient::GlslPairGradient(const gl::GlContextOptions& context)
    : GlslPairGradient(std::make_unique<gl::GlContext>(context)) {}

GlslPairGradient::GlslPairGradient(std::unique_ptr<gl::GlContext> context)
    : impl_(std::make_unique<Impl>()) {
  impl_->context = std::move(context);
  if (!impl_->context->IsCurrent()) impl_->context->MakeCurrent();
  impl_->sample =
      std::make_unique<gl::ShaderProgram>(gl::ShaderProgram::FromEmbedded({"refine_sample.comp"}));
  impl_->blur =
      std::make_unique<gl::ShaderProgram>(gl::ShaderProgram::FromEmbedded({"refine_blur.comp"}));
  impl_->coefficients = std::make_unique<gl::ShaderProgram>(
      gl::ShaderProgram::FromEmbedded({"refine_coefficients.comp"}));
  impl_->chain =
      std::make_unique<gl::ShaderProgram>(gl::ShaderProgram::FromEmbedded({"refine_chain.comp"}));
  // Bound only while computing, so any thread may compute (workers use a thread per job).
  impl_->context->ReleaseCurrent();
}

GlslPairGradient::~GlslPairGradient() {
  if (!impl_->context->IsCurrent()) impl_->context->MakeCurrent();
  // GL objects before their context.
  impl_->maps.reset();
  impl_->faces = gl::Buffer();
  impl_->weights = gl::Buffer();
  impl_->sample.reset();
  impl_->blur.reset();
  impl_->coefficients.reset();
  impl_->chain.reset();
  impl_->seen.reset();
  impl_->shadow.reset();
  impl_->renderer.reset();
}

const gl::GlInfo& GlslPairGradient::gl_info() const { return impl_->context->info(); }

PairGradient GlslPairGradient::Compute(const Mesh& mesh, const RefineView& reference,
                                       const RefineView& neighbour, const RefineOptions& options) {
  if (!impl_->context->IsCurrent()) impl_->context->MakeCurrent();
  struct Release {
    const gl::GlContext* context;
    ~Release() { context->ReleaseCurrent(); }
  } release{impl_->context.get()};
  return impl_->Compute(mesh, reference, neighbour, options);
}

}  // namespace ms
