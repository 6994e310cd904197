#include "gl/mesh_renderer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "base/check.h"
#include "base/error.h"
#include "gl/context.h"
#include "gl/gl_api.h"
#include "gl/projection.h"

namespace ms::gl {
namespace {

void CheckView(const View& view, const GlContext& context, int scale = 1) {
  const Intrinsics& k = view.intrinsics;
  if (!(k.width > 0 && k.height > 0 && k.fx > 0 && k.fy > 0 && std::isfinite(k.fx) &&
        std::isfinite(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy))) {
    throw InputError(
        fmt::format("view '{}': cannot render with intrinsics {}x{} f=({}, {}) "
                    "c=({}, {})",
                    view.name, k.width, k.height, k.fx, k.fy, k.cx, k.cy));
  }
  const int limit = context.info().max_texture_size;
  if (limit > 0 && (int64_t{k.width} * scale > limit || int64_t{k.height} * scale > limit)) {
    throw InputError(
        fmt::format("view '{}': {}x{} (x{} supersampling) exceeds the renderer's "
                    "limit of {} pixels per side",
                    view.name, k.width, k.height, scale, limit));
  }
  if (!view.R.allFinite() || !view.t.allFinite()) {
    throw InputError("view '" + view.name + "': pose is not finite");
  }
}

// Depth range for a render: the options' if given, else the mesh bounds'.
bool ChooseDepthRange(const GlContext& context, const GpuMesh& mesh, const View& view,
                      double near_option, double far_option, double* near, double* far) {
  double auto_near = 0, auto_far = 0;
  if (!mesh.DepthBounds(view, &auto_near, &auto_far)) return false;
  // Without reversed-Z (no glClipControl) depth precision degrades with far/near: keep the
  // ratio at most 1e4 (surfaces closer than far/1e4 are then clipped).
  if (!context.info().clip_control) auto_near = std::max(auto_near, auto_far * 1e-4);
  *near = near_option > 0 ? near_option : auto_near;
  *far = far_option > 0 ? far_option : auto_far;
  return *far > *near;
}

// Sets the depth state for DepthRange; returns the range to build the projection with.
DepthRange ApplyDepthState(const GlContext& context) {
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
  if (context.info().clip_control) {
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glDepthFunc(GL_GREATER);
    return DepthRange::kReversedZeroToOne;
  }
  glDepthFunc(GL_LESS);
  return DepthRange::kNegativeOneToOne;
}

float ClearDepthFor(DepthRange range) { return range == DepthRange::kReversedZeroToOne ? 0 : 1; }

void RestoreDefaultDepthState(const GlContext& context) {
  if (context.info().clip_control) glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
}

void ApplyCulling(bool cull) {
  if (cull) {
    glEnable(GL_CULL_FACE);
    glFrontFace(GL_CW);  // see gl/projection.h: front faces are clockwise in window space
    glCullFace(GL_BACK);
  } else {
    glDisable(GL_CULL_FACE);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

GpuMesh::GpuMesh(const Mesh& mesh) {
  num_vertices_ = mesh.vertices.size();
  num_faces_ = mesh.faces.size();
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      throw InputError(fmt::format("mesh: vertex {} is not finite", i));
    }
    bounds_.Extend(mesh.vertices[i]);
  }
  if (!bounds_.Empty()) origin_ = bounds_.Center();
  std::vector<float> positions;
  positions.reserve(3 * num_vertices_);
  for (const Eigen::Vector3d& v : mesh.vertices) {
    for (int c = 0; c < 3; ++c) positions.push_back(static_cast<float>(v[c] - origin_[c]));
  }
  std::vector<uint32_t> indices;
  indices.reserve(3 * num_faces_);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int32_t v : mesh.faces[f]) {
      if (v < 0 || static_cast<size_t>(v) >= num_vertices_) {
        throw InputError(fmt::format("mesh: face {} refers to vertex {}, but there are {}", f, v,
                                     num_vertices_));
      }
      indices.push_back(static_cast<uint32_t>(v));
    }
  }
  vertices_ = Buffer::FromVector(positions);
  indices_ = Buffer::FromVector(indices);
  vao_.SetFloatAttribute(0, vertices_, 3);
  vao_.SetIndexBuffer(indices_);
  CheckGlError("uploading a mesh");
}

void GpuMesh::Draw() const {
  if (num_faces_ > 0) vao_.DrawIndexedTriangles(3 * num_faces_);
}

bool GpuMesh::DepthBounds(const View& view, double* near, double* far) const {
  if (bounds_.Empty()) return false;
  double z_min = INFINITY, z_max = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p((corner & 1) ? bounds_.max.x() : bounds_.min.x(),
                            (corner & 2) ? bounds_.max.y() : bounds_.min.y(),
                            (corner & 4) ? bounds_.max.z() : bounds_.min.z());
    const double z = view.ToCamera(p).z();
    z_min = std::min(z_min, z);
    z_max = std::max(z_max, z);
  }
  if (!(z_max > 0)) return false;
  // Reversed-Z float depth keeps relative precision down to tiny near planes; 1e-6 of the far
  // distance still leaves ~1e-7 relative depth resolution over the range.
  // Pad so that float rounding in the vertex stage never clips a surface lying at the box's
  // extremes (a plane facing the camera has z_min == z_max).
  const double pad = 1e-3 * (z_max - z_min) + 1e-3 * z_max;
  *near = std::max(z_min - pad, z_max * 1e-6);
  *far = z_max + pad;
  return true;
}

// ---------------------------------------------------------------------------------------------

void DepthRenderOptions::Check() const {
  if (!(near >= 0) || !std::isfinite(near)) throw InputError("depth.near: must be >= 0");
  if (!(far >= 0) || !std::isfinite(far)) throw InputError("depth.far: must be >= 0");
  if (near > 0 && far > 0 && far <= near) throw InputError("depth.far: must exceed depth.near");
}

int64_t DepthMaps::CountValid() const { return depth.empty() ? 0 : cv::countNonZero(depth > 0); }

struct MeshRenderer::Impl {
  const GlContext* context;
  GpuMesh mesh;
  ShaderProgram program;
  std::unique_ptr<Framebuffer> framebuffer;

  Impl(const GlContext& c, const Mesh& m)
      : context(&c),
        mesh(m),
        program(ShaderProgram::FromEmbedded({"mesh_depth.vert", "mesh_depth.frag"})) {}
};

MeshRenderer::MeshRenderer(const GlContext& context, const Mesh& mesh) {
  if (!context.IsCurrent()) context.MakeCurrent();
  impl_ = std::make_unique<Impl>(context, mesh);
}

MeshRenderer::~MeshRenderer() = default;

const GpuMesh& MeshRenderer::mesh() const { return impl_->mesh; }

void MeshRenderer::SetMesh(const Mesh& mesh) {
  const GlContext& context = *impl_->context;
  if (!context.IsCurrent()) context.MakeCurrent();
  impl_->mesh = GpuMesh(mesh);
}

bool MeshRenderer::RenderTargets(const View& view, const DepthRenderOptions& options,
                                 std::unique_ptr<Framebuffer>* target) {
  options.Check();
  const GlContext& context = *impl_->context;
  if (!context.IsCurrent()) context.MakeCurrent();
  CheckView(view, context);
  const int width = view.intrinsics.width, height = view.intrinsics.height;
  std::unique_ptr<Framebuffer>& fb = *target;
  if (!fb || fb->width() != width || fb->height() != height) {
    fb = std::make_unique<Framebuffer>(
        width, height,
        std::vector<TextureFormat>{TextureFormat::kR32F, TextureFormat::kRGBA32F,
                                   TextureFormat::kR32I});
  }
  fb->Bind();
  fb->Clear(0, Eigen::Vector4f::Zero());
  fb->Clear(1, Eigen::Vector4f::Zero());
  fb->ClearInt(2, Eigen::Vector4i::Constant(-1));
  double near = 0, far = 0;
  if (impl_->mesh.num_faces() == 0 ||
      !ChooseDepthRange(context, impl_->mesh, view, options.near, options.far, &near, &far)) {
    return false;  // nothing in front of the camera
  }
  const DepthRange range = ApplyDepthState(context);
  fb->ClearDepth(ClearDepthFor(range));
  ApplyCulling(options.cull_back_faces);
  glDisable(GL_BLEND);

  const ShaderProgram& program = impl_->program;
  program.Set("u_model_view", ModelView(view, impl_->mesh.origin()).cast<float>().eval());
  program.Set("u_projection", GlProjection(view.intrinsics, near, far, range).cast<float>().eval());
  program.Set("u_origin", impl_->mesh.origin().cast<float>().eval());
  program.Use();
  impl_->mesh.Draw();
  RestoreDefaultDepthState(context);
  CheckGlError("rendering depth");
  return true;
}

DepthMaps MeshRenderer::Render(const View& view, const DepthRenderOptions& options) {
  const int width = view.intrinsics.width, height = view.intrinsics.height;
  DepthMaps maps;
  if (!RenderTargets(view, options, &impl_->framebuffer)) {
    maps.depth = cv::Mat::zeros(height, width, CV_32F);
    if (options.world_positions) maps.world = cv::Mat::zeros(height, width, CV_32FC3);
    if (options.face_ids) maps.face_id = cv::Mat(height, width, CV_32S, cv::Scalar(-1));
    return maps;
  }
  const Framebuffer& fb = *impl_->framebuffer;
  maps.depth = fb.Read(0);
  if (options.world_positions) {
    const cv::Mat world4 = fb.Read(1);
    cv::cvtColor(world4, maps.world, cv::COLOR_BGRA2BGR);  // drops w, keeps x,y,z order
  }
  if (options.face_ids) maps.face_id = fb.Read(2);
  return maps;
}

// ---------------------------------------------------------------------------------------------

void SurfaceMaterial::Check(const std::string& field) const {
  if (!color.allFinite() || (color.array() < 0).any() || (color.array() > 1).any()) {
    throw InputError(field + ".color: components must be in [0, 1]");
  }
  if (!(noise_contrast >= 0 && noise_contrast <= 2)) {
    throw InputError(field + ".noise_contrast: must be in [0, 2]");
  }
  if (!(noise_period > 0) || !std::isfinite(noise_period)) {
    throw InputError(field + ".noise_period: must be > 0");
  }
  if (!(photo_period > 0) || !std::isfinite(photo_period)) {
    throw InputError(field + ".photo_period: must be > 0");
  }
  if (!(photo_weight >= 0 && photo_weight <= 1)) {
    throw InputError(field + ".photo_weight: must be in [0, 1]");
  }
  if (!(window_spacing >= 0) || !std::isfinite(window_spacing)) {
    throw InputError(field + ".window_spacing: must be >= 0");
  }
  if (!(floor_height > 0) || !std::isfinite(floor_height)) {
    throw InputError(field + ".floor_height: must be > 0");
  }
  if (!(window_width > 0 && window_width < 1)) {
    throw InputError(field + ".window_width: must be in (0, 1)");
  }
  if (!(window_height > 0 && window_height < 0.7f)) {
    throw InputError(field + ".window_height: must be in (0, 0.7)");
  }
}

void SurfaceTexture::Check(size_t num_faces) const {
  if (materials.empty()) throw InputError("texture.materials: at least one is needed");
  for (size_t i = 0; i < materials.size(); ++i) {
    materials[i].Check("texture.materials[" + std::to_string(i) + "]");
    if (materials[i].photo >= static_cast<int>(photos.size())) {
      throw InputError(fmt::format("texture.materials[{}].photo: {} but only {} photo(s)", i,
                                   materials[i].photo, photos.size()));
    }
  }
  if (!face_material.empty() && face_material.size() != num_faces) {
    throw InputError(fmt::format("texture.face_material: {} entries for {} faces",
                                 face_material.size(), num_faces));
  }
  for (size_t f = 0; f < face_material.size(); ++f) {
    if (face_material[f] < 0 || face_material[f] >= static_cast<int32_t>(materials.size())) {
      throw InputError(
          fmt::format("texture.face_material[{}]: {} is not a material", f, face_material[f]));
    }
  }
  for (size_t i = 0; i < photos.size(); ++i) {
    if (photos[i].empty() || photos[i].type() != CV_8UC3) {
      throw InputError(fmt::format("texture.photos[{}]: must be a non-empty 8-bit BGR image", i));
    }
  }
  if (photo_size < 16 || photo_size > 8192) {
    throw InputError("texture.photo_size: must be in [16, 8192]");
  }
  if (noise_octaves < 1 || noise_octaves > 16) {
    throw InputError("texture.noise_octaves: must be in [1, 16]");
  }
  if (!up.allFinite() || up.norm() < 1e-6) throw InputError("texture.up: must be a direction");
}

void SurfaceRenderOptions::Check() const {
  if (supersampling < 1 || supersampling > 8) {
    throw InputError("render.supersampling: must be in [1, 8]");
  }
  if (!light_direction.allFinite() || light_direction.norm() < 1e-9) {
    throw InputError("render.light_direction: must be a non-zero direction");
  }
  if (!(ambient >= 0 && ambient <= 1)) throw InputError("render.ambient: must be in [0, 1]");
  if (!background.allFinite()) throw InputError("render.background: must be finite");
  DepthRenderOptions{near, far}.Check();
}

struct SurfaceRenderer::Impl {
  const GlContext* context;
  GpuMesh mesh;
  ShaderProgram program;
  Buffer face_data;
  Buffer materials;
  std::unique_ptr<Texture2DArray> photos;
  int num_photos = 0;
  SurfaceTexture texture;
  std::unique_ptr<Framebuffer> framebuffer;

  Impl(const GlContext& c, const Mesh& m, const SurfaceTexture& t)
      : context(&c),
        mesh(m),
        program(ShaderProgram::FromEmbedded({"surface.vert", "surface.frag"})),
        texture(t) {
    texture.photos.clear();  // uploaded below; no need to keep a copy
    std::vector<Eigen::Vector4f> faces(std::max<size_t>(m.faces.size(), 1),
                                       Eigen::Vector4f::Zero());
    for (size_t f = 0; f < m.faces.size(); ++f) {
      const int material = t.face_material.empty() ? 0 : t.face_material[f];
      faces[f] << m.FaceNormal(f).cast<float>(), static_cast<float>(material);
    }
    face_data = Buffer::FromVector(faces);
    std::vector<Eigen::Vector4f> packed;
    for (const SurfaceMaterial& s : t.materials) {
      packed.emplace_back(s.color.x(), s.color.y(), s.color.z(), s.noise_contrast);
      packed.emplace_back(s.noise_period, s.photo_period, static_cast<float>(s.photo),
                          s.photo_weight);
      packed.emplace_back(s.window_spacing, s.floor_height, s.window_width, s.window_height);
    }
    materials = Buffer::FromVector(packed);
    num_photos = static_cast<int>(t.photos.size());
    const int size = t.photo_size;
    const int levels = 1 + static_cast<int>(std::floor(std::log2(size)));
    photos = std::make_unique<Texture2DArray>(size, size, std::max(num_photos, 1),
                                              TextureFormat::kRGBA8, levels);
    for (int i = 0; i < num_photos; ++i) {
      cv::Mat resized, rgba;
      cv::resize(t.photos[i], resized, cv::Size(size, size), 0, 0, cv::INTER_AREA);
      cv::cvtColor(resized, rgba, cv::COLOR_BGR2RGBA);
      photos->UploadLayer(i, rgba);
    }
    if (num_photos == 0) {
      photos->UploadLayer(0, cv::Mat(size, size, CV_8UC4, cv::Scalar(128, 128, 128, 255)));
    }
    photos->GenerateMipmaps();
    photos->SetFilter(TextureFilter::kLinearMipmap);
    photos->SetWrap(TextureWrap::kRepeat);
    CheckGlError("preparing surface textures");
  }
};

SurfaceRenderer::SurfaceRenderer(const GlContext& context, const Mesh& mesh,
                                 const SurfaceTexture& texture) {
  texture.Check(mesh.faces.size());
  if (!context.IsCurrent()) context.MakeCurrent();
  impl_ = std::make_unique<Impl>(context, mesh, texture);
}

SurfaceRenderer::~SurfaceRenderer() = default;

cv::Mat SurfaceRenderer::Render(const View& view, const SurfaceRenderOptions& options) {
  options.Check();
  const GlContext& context = *impl_->context;
  if (!context.IsCurrent()) context.MakeCurrent();
  CheckView(view, context, options.supersampling);
  const int s = options.supersampling;
  View big = view;
  big.intrinsics.width *= s;
  big.intrinsics.height *= s;
  // Corner-origin pixel coordinates scale exactly: x_big = s * x.
  big.intrinsics.fx *= s;
  big.intrinsics.fy *= s;
  big.intrinsics.cx *= s;
  big.intrinsics.cy *= s;
  const int width = big.intrinsics.width, height = big.intrinsics.height;
  const Eigen::Vector3f bg = options.background;
  cv::Mat image;
  double near = 0, far = 0;
  if (impl_->mesh.num_faces() > 0 &&
      ChooseDepthRange(context, impl_->mesh, big, options.near, options.far, &near, &far)) {
    std::unique_ptr<Framebuffer>& fb = impl_->framebuffer;
    if (!fb || fb->width() != width || fb->height() != height) {
      fb = std::make_unique<Framebuffer>(width, height,
                                         std::vector<TextureFormat>{TextureFormat::kRGBA8});
    }
    fb->Bind();
    const DepthRange range = ApplyDepthState(context);
    fb->Clear(0, Eigen::Vector4f(bg.x(), bg.y(), bg.z(), 1));
    fb->ClearDepth(ClearDepthFor(range));
    ApplyCulling(false);
    glDisable(GL_BLEND);
    const ShaderProgram& p = impl_->program;
    p.Set("u_model_view", ModelView(big, impl_->mesh.origin()).cast<float>().eval());
    p.Set("u_projection", GlProjection(big.intrinsics, near, far, range).cast<float>().eval());
    p.Set("u_origin", impl_->mesh.origin().cast<float>().eval());
    p.Set("u_light_dir", options.light_direction.normalized().cast<float>().eval());
    p.Set("u_ambient", static_cast<float>(options.ambient));
    p.Set("u_up", impl_->texture.up.normalized().eval());
    p.Set("u_seed", impl_->texture.seed);
    p.Set("u_num_photos", impl_->num_photos);
    p.Set("u_octaves", impl_->texture.noise_octaves);
    p.Set("u_photos", 0);
    impl_->photos->Bind(0);
    impl_->face_data.BindStorage(0);
    impl_->materials.BindStorage(1);
    p.Use();
    impl_->mesh.Draw();
    RestoreDefaultDepthState(context);
    CheckGlError("rendering a textured image");
    cv::cvtColor(fb->Read(0), image, cv::COLOR_RGBA2BGR);
  } else {
    image = cv::Mat(height, width, CV_8UC3,
                    cv::Scalar(std::lround(bg.z() * 255), std::lround(bg.y() * 255),
                               std::lround(bg.x() * 255)));
  }
  if (s == 1) return image;
  cv::Mat small;
  cv::resize(image, small, cv::Size(view.intrinsics.width, view.intrinsics.height), 0, 0,
             cv::INTER_AREA);
  return small;
}

}  // namespace ms::gl
