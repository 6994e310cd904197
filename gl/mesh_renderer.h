// Rendering meshes from calibrated cameras: exact per-pixel depth, world position and face
// index (MeshRenderer), and textured, lit images for synthetic datasets (SurfaceRenderer).
// Both follow gl/projection.h: image row r = framebuffer row r, pixel centres at +0.5, depth =
// camera z, lens distortion ignored. A GlContext must be current (gl/context.h).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "gl/context.h"
#include "gl/objects.h"
#include "mesh/mesh.h"
#include "scene/camera.h"
#include "scene/scene.h"

namespace ms::gl {

// A Mesh in GL buffers: float positions relative to origin() (the bounding-box centre) at
// attribute 0 of vertex_array(), uint32 indices, one triangle per face in face order (so
// gl_PrimitiveID = face index).
class GpuMesh {
 public:
  // Throws InputError if a face refers to a vertex that does not exist, or a vertex is not finite.
  explicit GpuMesh(const Mesh& mesh);

  void Draw() const;  // all faces, with the current program and framebuffer
  const Eigen::Vector3d& origin() const { return origin_; }
  const BoundingBox& bounds() const { return bounds_; }
  size_t num_faces() const { return num_faces_; }
  size_t num_vertices() const { return num_vertices_; }
  const VertexArray& vertex_array() const { return vao_; }
  const Buffer& vertex_buffer() const { return vertices_; }
  const Buffer& index_buffer() const { return indices_; }

  // A [near, far] that holds the whole bounding box in front of `view`; false if it lies
  // entirely behind the camera.
  bool DepthBounds(const View& view, double* near, double* far) const;

 private:
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  BoundingBox bounds_;
  size_t num_faces_ = 0, num_vertices_ = 0;
  Buffer vertices_, indices_;
  VertexArray vao_;
};

struct DepthRenderOptions {
  double near = 0;               // nearest depth kept; 0: from the mesh bounding box (see GpuMesh)
  double far = 0;                // farthest depth kept; 0: from the mesh bounding box
  bool cull_back_faces = false;  // drop faces seen from behind (conventions: CCW from outside)
  bool world_positions = true;   // fill DepthMaps::world
  bool face_ids = true;          // fill DepthMaps::face_id
  void Check() const;            // throws InputError naming the field
};

struct DepthMaps {
  cv::Mat depth;               // CV_32F, camera z of the nearest surface; 0 where none
  cv::Mat world;               // CV_32FC3 world position (x,y,z); 0 where none; empty if not asked
  cv::Mat face_id;             // CV_32S mesh face index; -1 where none; empty if not asked
  int64_t CountValid() const;  // pixels with depth > 0
};

class MeshRenderer {
 public:
  MeshRenderer(const GlContext& context, const Mesh& mesh);
  ~MeshRenderer();
  MeshRenderer(const MeshRenderer&) = delete;
  MeshRenderer& operator=(const MeshRenderer&) = delete;

  // Renders at view.intrinsics.width x height. Throws InputError for a view with bad
  // intrinsics or a size above the driver's limit.
  DepthMaps Render(const View& view, const DepthRenderOptions& options = {});
  // The same rendering left on the GPU for later passes: `target` is (re)made at the view's size
  // when it does not fit, with attachments 0 depth (R32F), 1 world (RGBA32F), 2 face id (R32I),
  // cleared to 0, 0, -1. False, with the target cleared, when nothing lies in front of the view.
  bool RenderTargets(const View& view, const DepthRenderOptions& options,
                     std::unique_ptr<Framebuffer>* target);
  // Replaces the mesh; the program and framebuffers stay.
  void SetMesh(const Mesh& mesh);
  const GpuMesh& mesh() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What a surface looks like. Colours are linear RGB in [0,1]; lengths are in scene units.
struct SurfaceMaterial {
  Eigen::Vector3f color{0.6f, 0.55f, 0.5f};  // mean albedo
  float noise_contrast = 0.6f;               // amplitude of the multi-scale noise (0 = flat colour)
  float noise_period = 1.0f;                 // size of the coarsest noise octave
  int photo = -1;                            // index into SurfaceTexture::photos; -1: noise only
  float photo_period = 2.0f;                 // world size one photo covers (tri-planar projection)
  float photo_weight = 0.8f;                 // share of the photo in the albedo
  float window_spacing = 0;                  // facade windows every this much along walls; 0 = none
  float floor_height = 3.0f;                 // window rows every this much upwards
  float window_width = 0.45f;                // window width as a share of window_spacing
  float window_height = 0.5f;                // window height as a share of floor_height
  void Check(const std::string& field) const;  // throws InputError naming field.<member>
};

struct SurfaceTexture {
  std::vector<SurfaceMaterial> materials{SurfaceMaterial{}};  // at least one
  std::vector<int32_t> face_material;  // per face; empty = material 0 everywhere
  std::vector<cv::Mat> photos;         // CV_8UC3 BGR, any size (resized to photo_size square)
  int photo_size = 1024;
  uint32_t seed = 1;                   // noise pattern
  int noise_octaves = 7;               // finest detail = noise_period / 2^(octaves-1)
  Eigen::Vector3f up{0, 0, 1};         // world up, for facade windows
  void Check(size_t num_faces) const;  // throws InputError naming the field
};

struct SurfaceRenderOptions {
  int supersampling = 3;  // render at k times the resolution, then area-average (anti-aliasing)
  Eigen::Vector3d light_direction{0.4, -0.3, 1.0};  // towards the light (normalised internally)
  double ambient = 0.45;                            // share of non-directional light
  Eigen::Vector3f background{0.55f, 0.6f, 0.65f};   // linear RGB where no surface
  double near = 0, far = 0;                         // as DepthRenderOptions
  void Check() const;
};

class SurfaceRenderer {
 public:
  SurfaceRenderer(const GlContext& context, const Mesh& mesh, const SurfaceTexture& texture);
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  // CV_8UC3 BGR image of view.intrinsics.width x height.
  cv::Mat Render(const View& view, const SurfaceRenderOptions& options = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ms::gl
