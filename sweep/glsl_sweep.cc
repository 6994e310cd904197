#include "sweep/glsl_sweep.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/core.hpp>

#include "base/check.h"
#include "base/error.h"
#include "base/log.h"
#include "gl/context.h"
#include "gl/gl_api.h"
#include "gl/mesh_renderer.h"
#include "gl/objects.h"
#include "gl/projection.h"
#include "shaders/shaders.h"

namespace ms {
namespace {

constexpr float kUndefinedNcc = -2.0f;  // an undefined NCC (the reference's NaN): below all
// Outputs per invocation of the unrolled blur: 8 is as fast as 16 or 24 on llvmpipe and halves
// the JIT time of the unrolled code (about a second per window size).
constexpr int kUnrolledBlock = 8;
constexpr int64_t kMaxFaces = int64_t{1} << 24;  // face ids travel as exact floats
constexpr char kUnrolledMarker[] = "// @MS_UNROLLED_TAPS@";

// ---- Shader sources ----

// The tap loop of sweep_blur.glsl fully unrolled, on one line (so line numbers do not move):
// every sample loaded once, then each output's 2 radius + 1 taps.
std::string UnrolledTaps(int radius, int block) {
  std::string s;
  const int samples = block + 2 * radius;
  for (int i = 0; i < samples; ++i) s += fmt::format("Sums s{0} = LoadSample({0}); ", i);
  for (int o = 0; o < block; ++o) {
    s += "{ Sums acc = ZeroSums(); ";
    for (int i = 0; i <= 2 * radius; ++i) {
      s += fmt::format("Tap(acc, u_weights[{}], s{}); ", i, o + i);
    }
    s += fmt::format("FinishOutput({}, acc); }} ", o);
  }
  return s;
}

gl::ShaderSource Source(const std::string& name, const std::vector<std::string>& defines,
                        const std::string& unrolled = {}) {
  gl::ShaderSource source;
  source.stage = gl::ShaderStageFromName(name);
  source.name = name;
  std::string text = shaders::Expand(name, &source.included_names);
  if (!unrolled.empty()) {
    const size_t at = text.find(kUnrolledMarker);
    MS_CHECK(at != std::string::npos) << name << " has no unrolling marker";
    text.replace(at, sizeof(kUnrolledMarker) - 1, unrolled);
  }
  source.text = gl::InsertDefines(text, defines);
  return source;
}

gl::ShaderProgram Program(const std::string& name, const std::vector<std::string>& names,
                          const std::vector<std::string>& defines,
                          const std::string& unrolled = {}) {
  std::vector<gl::ShaderSource> sources;
  for (const std::string& n : names) sources.push_back(Source(n, defines, unrolled));
  return gl::ShaderProgram(name, sources);
}

// The farthest camera z any swept vertex can reach (sweeping moves a vertex by at most
// |alpha k_max| along a ray), padded; 0 if the mesh lies behind the camera.
double FarPlane(const View& view, const Mesh& mesh, double max_shift) {
  double z_max = -std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& v : mesh.vertices) z_max = std::max(z_max, view.ToCamera(v).z());
  z_max += max_shift;
  if (!(z_max > 0)) return 0;
  return z_max * 1.01 + 1e-9;
}

}  // namespace

void GlslSweepKernelOptions::Check() const {
  context.Check();
  if (blur_block < 0 || blur_block > 64) {
    throw InputError(
        fmt::format("glsl.blur_block must be in [0, 64] (0 = auto), got {}", blur_block));
  }
  if (max_batch_bytes < 0) {
    throw InputError(
        fmt::format("glsl.max_batch_bytes must be >= 0 (0 = auto), got {}", max_batch_bytes));
  }
  if (max_batch_offsets < 0) {
    throw InputError(fmt::format("glsl.max_batch_offsets must be >= 0 (0 = as many as fit), got {}",
                                 max_batch_offsets));
  }
}

// ---------------------------------------------------------------------------------------------

// Neighbours reprojected by one dispatch, at most.
constexpr int kMaxReprojectGroup = 7;

struct GlslSweepKernel::Impl {
  std::unique_ptr<gl::GlContext> owned_context;
  const gl::GlContext* context = nullptr;
  GlslSweepKernelOptions options;
  GlslBlurVariant variant = GlslBlurVariant::kLoops;
  int block = 1;
  int local_x = 64, local_y = 1;  // blur passes' work-group shape
  int max_shared_bytes = 0;       // per work group
  int max_array_layers = 0;
  int max_group = 1;  // neighbours reprojected by one dispatch (image units - 1)

  std::unique_ptr<gl::ShaderProgram> raster_depth, raster_surface;
  std::map<int, std::unique_ptr<gl::ShaderProgram>> reproject;  // by neighbours per dispatch
  struct BlurPrograms {
    gl::ShaderProgram rows, ncc;
  };
  std::map<int, std::unique_ptr<BlurPrograms>> blur;            // by window radius
  std::map<int, std::unique_ptr<gl::ShaderProgram>> tile_best;  // by radius and bit words

  // Textures kept between jobs of the same shape (sizes, batch, radius, neighbours).
  struct Resources {
    std::vector<int> key;
    std::unique_ptr<gl::Texture2DArray> surface, surface_depth, world, ncc;
    // Each neighbour's NCC at k = 0 (layer j), which the other offsets must beat (WinnerRule).
    std::unique_ptr<gl::Texture2DArray> unswept_ncc;
    std::vector<std::unique_ptr<gl::Texture2DArray>> reprojected;  // per neighbour
    std::vector<std::unique_ptr<gl::Texture2DArray>> shadow, shadow_depth;
    std::unique_ptr<gl::LayeredFramebuffer> surface_target;
    std::vector<std::unique_ptr<gl::LayeredFramebuffer>> shadow_targets;
    std::unique_ptr<gl::Texture2D> sums0, sums1;
  };
  Resources resources;

  void Init(const GlslSweepKernelOptions& o) {
    o.Check();
    options = o;
    const gl::GlInfo& info = context->info();
    variant = o.blur;
    if (variant == GlslBlurVariant::kAuto) {
      variant = info.software ? GlslBlurVariant::kUnrolled : GlslBlurVariant::kLoops;
    }
    const bool unrolled = variant == GlslBlurVariant::kUnrolled;
    block = o.blur_block > 0 ? o.blur_block : (unrolled ? kUnrolledBlock : 1);
    // Unrolled: 8x8 invocations (llvmpipe runs 8 lanes at a time, lanes along a line's
    // blocks); loops: 64 invocations along image rows (coalesced on GPUs).
    local_x = unrolled ? 8 : 64;
    local_y = unrolled ? 8 : 1;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_array_layers);
    glGetIntegerv(GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, &max_shared_bytes);
    GLint image_units = 0, texture_units = 0;
    glGetIntegerv(GL_MAX_COMPUTE_IMAGE_UNIFORMS, &image_units);
    glGetIntegerv(GL_MAX_COMPUTE_TEXTURE_IMAGE_UNITS, &texture_units);
    // The world image and one per neighbour; C's image, the surface, two per neighbour. At most
    // kMaxReprojectGroup: llvmpipe loses reprojections in groups of 9 or more though it reports
    // 32 image and texture units (GlslSweepTest.ManyNeighboursAndPyramidLevels).
    max_group =
        std::max(1, std::min({kMaxReprojectGroup, image_units - 1, (texture_units - 2) / 2}));
    raster_depth = std::make_unique<gl::ShaderProgram>(
        Program("sweep raster (shadow maps)",
                {"sweep_raster.vert", "sweep_raster.geom", "sweep_raster_depth.frag"},
                options.shader_defines));
    raster_surface = std::make_unique<gl::ShaderProgram>(Program(
        "sweep raster (C)", {"sweep_raster.vert", "sweep_raster.geom", "sweep_raster_surface.frag"},
        options.shader_defines));
    // The default job's programs (sigma 8 px, two neighbours), so that a driver that cannot
    // compile them fails here rather than in the first job.
    Reproject(std::min(2, max_group));
    const int radius = static_cast<int>(std::ceil(3 * SweepOptions().gaussian_sigma_px));
    Blur(radius);
    TileBest(radius, 1);
  }

  // Texture units: I_C 0, neighbour images 1..n, shadow maps n+1..2n, C's surface 2n+1.
  // Image units: world 0, reprojections 1..n.
  gl::ShaderProgram& Reproject(int neighbours) {
    auto& slot = reproject[neighbours];
    if (!slot) {
      std::vector<std::string> defines = {fmt::format("NEIGHBOURS {}", neighbours)};
      defines.insert(defines.end(), options.shader_defines.begin(), options.shader_defines.end());
      slot = std::make_unique<gl::ShaderProgram>(
          Program("sweep world + reprojection", {"sweep_reproject.comp"}, defines));
      slot->Set("u_image", 0);
      for (int j = 0; j < neighbours; ++j) {
        slot->Set(fmt::format("u_neighbour[{}]", j), 1 + j);
        slot->Set(fmt::format("u_shadow[{}]", j), 1 + neighbours + j);
      }
      slot->Set("u_surface", 1 + 2 * neighbours);
    }
    return *slot;
  }

  // The loops variant with one output per invocation stages the blur passes' samples in shared
  // memory (sweep_blur_rows.comp, sweep_blur_ncc.comp): rows in groups of local_x, columns in
  // tiles of NccTile() outputs; unless a window that wide (24 bytes a sample) would not fit
  // the shared memory.
  bool Tiled(int radius) const {
    const Eigen::Vector2i tile = NccTile(radius);
    return variant == GlslBlurVariant::kLoops && block == 1 &&
           (local_x + 2 * radius) * 24 <= max_shared_bytes &&
           (tile.y() + 2 * radius) * tile.x() * 24 <= max_shared_bytes;
  }
  // 16 x 16 outputs, fewer columns where the 2 radius + 16 rows of sums would not fit.
  Eigen::Vector2i NccTile(int radius) const {
    const int rows = 16;
    int columns = 16;
    while (columns > 1 && (rows + 2 * radius) * columns * 24 > max_shared_bytes) columns /= 2;
    return {columns, rows};
  }

  std::vector<std::string> ComputeDefines(int radius, int match_words) const {
    const bool unrolled = variant == GlslBlurVariant::kUnrolled;
    const Eigen::Vector2i tile = NccTile(radius);
    std::vector<std::string> defines = {
        fmt::format("RADIUS {}", radius), fmt::format("BLOCK {}", block),
        fmt::format("UNROLLED {}", unrolled ? 1 : 0),
        fmt::format("TRANSPOSED {}", unrolled ? 1 : 0), fmt::format("LOCAL_X {}", local_x),
        fmt::format("LOCAL_Y {}", local_y), fmt::format("UNDEFINED_NCC {:.1f}", kUndefinedNcc),
        // Tile-best work groups: 64 invocations for llvmpipe, 256 to fill a GPU's multiprocessors.
        fmt::format("REDUCE_THREADS {}", unrolled ? 64 : 256),
        fmt::format("MATCH_WORDS {}", match_words), fmt::format("TILED {}", Tiled(radius) ? 1 : 0),
        fmt::format("TILE_X {}", tile.x()), fmt::format("TILE_Y {}", tile.y())};
    defines.insert(defines.end(), options.shader_defines.begin(), options.shader_defines.end());
    return defines;
  }

  BlurPrograms& Blur(int radius) {
    auto& slot = blur[radius];
    if (!slot) {
      const std::vector<std::string> defines = ComputeDefines(radius, 1);
      const std::string taps =
          variant == GlslBlurVariant::kUnrolled ? UnrolledTaps(radius, block) : std::string();
      slot = std::make_unique<BlurPrograms>(
          BlurPrograms{Program("sweep row blur", {"sweep_blur_rows.comp"}, defines, taps),
                       Program("sweep column blur + NCC", {"sweep_blur_ncc.comp"}, defines, taps)});
    }
    return *slot;
  }

  // The tile-best pass reads C's padded render: it depends on the radius too.
  gl::ShaderProgram& TileBest(int radius, int match_words) {
    auto& slot = tile_best[radius * 1000 + match_words];
    if (!slot) {
      slot = std::make_unique<gl::ShaderProgram>(Program(
          "sweep tile-best", {"sweep_tile_best.comp"}, ComputeDefines(radius, match_words)));
    }
    return *slot;
  }

  // Padded width of C's targets: pixel x at column x + radius, zeros around (the row pass reads
  // radius columns beyond each side, and up to block - 1 more after the last block).
  int PaddedWidth(int width, int radius) const { return width + 2 * radius + block; }

  // `unswept`: keep the NCC maps at k = 0 too (WinnerRule::must_move).
  void Allocate(const PreparedSweep& prep, int batch_size, int radius, bool unswept);

  // Run and its stages (below): UploadJob puts a job on the GPU; each batch of offsets goes
  // through RenderShadowMaps, RenderCameraView, NccBatch and ReduceBatch; ReadBackWinners turns
  // the tile records into points. A CaptureRecorder copies one offset's images out between them.
  struct Batch;
  struct Group;
  struct GpuJob;
  class CaptureRecorder;
  SweepResult Run(GlslSweepKernel* kernel, const SweepJob& job, GlslSweepCapture* capture);
  void CheckLimits(const SweepJob& job, const PreparedSweep& prep,
                   const GlslSweepCapture* capture) const;
  std::unique_ptr<GpuJob> UploadJob(const SweepJob& job, const PreparedSweep& prep,
                                    const WinnerRule& rule, const MemoryPlan& plan);
  void RenderShadowMaps(const GpuJob& gpu, const Batch& batch);
  void RenderCameraView(const GpuJob& gpu, const Batch& batch);
  void NccBatch(const GpuJob& gpu, const Batch& batch);
  void KeepUnsweptNcc(const GpuJob& gpu);
  void ReduceBatch(const GpuJob& gpu, const Batch& batch);
  std::vector<SweepPoint> ReadBackWinners(const GpuJob& gpu, SweepStats* stats) const;
};

void GlslSweepKernel::Impl::Allocate(const PreparedSweep& prep, int batch_size, int radius,
                                     bool unswept) {
  const int width = prep.camera.view.intrinsics.width;
  const int height = prep.camera.view.intrinsics.height;
  const int num_neighbours = static_cast<int>(prep.neighbours.size());
  std::vector<int> key = {width, height, batch_size, radius, block, num_neighbours, unswept};
  for (const SweepCamera& n : prep.neighbours) {
    key.push_back(n.view.intrinsics.width);
    key.push_back(n.view.intrinsics.height);
  }
  if (resources.key == key) return;
  resources = Resources();
  resources.key = key;
  const int padded = PaddedWidth(width, radius);
  using gl::Texture2DArray;
  using gl::TextureFormat;
  resources.surface =
      std::make_unique<Texture2DArray>(padded, height, batch_size, TextureFormat::kRG32F);
  resources.surface_depth =
      std::make_unique<Texture2DArray>(padded, height, batch_size, TextureFormat::kDepth32F);
  resources.surface_target = std::make_unique<gl::LayeredFramebuffer>(
      std::vector<const Texture2DArray*>{resources.surface.get()}, *resources.surface_depth);
  resources.world =
      std::make_unique<Texture2DArray>(padded, height, batch_size, TextureFormat::kRGBA32F);
  for (int j = 0; j < num_neighbours; ++j) {
    resources.reprojected.push_back(
        std::make_unique<Texture2DArray>(padded, height, batch_size, TextureFormat::kRGBA32F));
    const Intrinsics& k = prep.neighbours[j].view.intrinsics;
    resources.shadow.push_back(
        std::make_unique<Texture2DArray>(k.width, k.height, batch_size, TextureFormat::kR32F));
    resources.shadow_depth.push_back(
        std::make_unique<Texture2DArray>(k.width, k.height, batch_size, TextureFormat::kDepth32F));
    resources.shadow_targets.push_back(std::make_unique<gl::LayeredFramebuffer>(
        std::vector<const Texture2DArray*>{resources.shadow.back().get()},
        *resources.shadow_depth.back()));
  }
  resources.ncc = std::make_unique<Texture2DArray>(width, height, batch_size * num_neighbours,
                                                   TextureFormat::kR32F);
  if (unswept) {
    resources.unswept_ncc =
        std::make_unique<Texture2DArray>(width, height, num_neighbours, TextureFormat::kR32F);
  }
  // Row sums, padded by zeros along the columns (transposed: along the rows); never written
  // outside the image afterwards.
  const bool transposed = variant == GlslBlurVariant::kUnrolled;
  const int sums_w = transposed ? height + 2 * radius + block : width;
  const int sums_h = transposed ? width : height + 2 * radius + block;
  resources.sums0 = std::make_unique<gl::Texture2D>(
      gl::Texture2D::FromImage(cv::Mat::zeros(sums_h, sums_w, CV_32FC4), TextureFormat::kRGBA32F));
  resources.sums1 = std::make_unique<gl::Texture2D>(
      gl::Texture2D::FromImage(cv::Mat::zeros(sums_h, sums_w, CV_32FC2), TextureFormat::kRG32F));
  gl::CheckGlError("allocating sweep textures");
}

GlslSweepKernel::GlslSweepKernel(const GlslSweepKernelOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->owned_context = std::make_unique<gl::GlContext>(options.context);
  impl_->context = impl_->owned_context.get();
  impl_->Init(options);
  // An owned context is bound only while the kernel works, so any thread may run it (the
  // worker process sweeps each job on a fresh thread).
  impl_->owned_context->ReleaseCurrent();
}

GlslSweepKernel::GlslSweepKernel(const gl::GlContext& context,
                                 const GlslSweepKernelOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->context = &context;
  if (!context.IsCurrent()) context.MakeCurrent();
  impl_->Init(options);
}

GlslSweepKernel::~GlslSweepKernel() {
  if (impl_->context != nullptr && !impl_->context->IsCurrent()) impl_->context->MakeCurrent();
  // GL objects before their context.
  impl_->resources = Impl::Resources();
  impl_->blur.clear();
  impl_->tile_best.clear();
  impl_->reproject.clear();
  impl_->raster_surface.reset();
  impl_->raster_depth.reset();
}

const gl::GlInfo& GlslSweepKernel::gl_info() const { return impl_->context->info(); }
GlslBlurVariant GlslSweepKernel::blur_variant() const { return impl_->variant; }
int GlslSweepKernel::blur_block() const { return impl_->block; }

GlslSweepKernel::MemoryPlan GlslSweepKernel::PlanMemory(const PreparedSweep& prep,
                                                        const WinnerRule& rule) const {
  const int64_t width = prep.camera.view.intrinsics.width;
  const int64_t height = prep.camera.view.intrinsics.height;
  const int64_t radius = (prep.window.rows - 1) / 2;
  const int64_t block = impl_->block;
  const int64_t padded = (width + 2 * radius + block) * height;
  const int64_t neighbours = static_cast<int64_t>(prep.neighbours.size());
  MemoryPlan plan;
  // Per offset: C's surface + depth, world and one reprojection per neighbour (padded), NCC
  // maps.
  plan.per_offset_bytes = padded * (8 + 4 + 16 + 16 * neighbours) + width * height * 4 * neighbours;
  // Per job: C's image, the row sums (RGBA32F + RG32F, padded), the NCC maps at k = 0 where
  // winners must move.
  plan.fixed_bytes = width * height * 4 + (height + 2 * radius + block) * width * (16 + 8);
  if (rule.must_move) plan.fixed_bytes += width * height * 4 * neighbours;
  for (const SweepCamera& n : prep.neighbours) {
    const int64_t n_pixels = int64_t{n.view.intrinsics.width} * n.view.intrinsics.height;
    plan.per_offset_bytes += n_pixels * (4 + 4);  // shadow map + its depth buffer
    plan.fixed_bytes += n_pixels * 4;             // the image
  }
  const int num_offsets = static_cast<int>(prep.offsets.size());
  int64_t budget = impl_->options.max_batch_bytes;
  if (budget == 0) budget = impl_->context->info().software ? int64_t{128} << 20 : int64_t{1} << 30;
  const int64_t room = std::max<int64_t>(0, budget - plan.fixed_bytes);
  int64_t fit =
      std::clamp<int64_t>(room / std::max<int64_t>(1, plan.per_offset_bytes), 1, num_offsets);
  if (impl_->options.max_batch_offsets > 0) {
    fit = std::min<int64_t>(fit, impl_->options.max_batch_offsets);
  }
  if (impl_->max_array_layers > 0) {
    fit = std::min<int64_t>(fit, std::max<int64_t>(1, impl_->max_array_layers / neighbours));
  }
  // Even batches: as many batches as needed, as small as possible.
  const int batches = gl::DivideRoundingUp(num_offsets, fit);
  plan.offsets_per_batch = gl::DivideRoundingUp(num_offsets, batches);
  return plan;
}

SweepResult GlslSweepKernel::Run(const SweepJob& job) { return Run(job, nullptr); }

SweepResult GlslSweepKernel::Run(const SweepJob& job, GlslSweepCapture* capture) {
  struct ReleaseOwned {
    const gl::GlContext* owned;
    ~ReleaseOwned() {
      if (owned != nullptr) owned->ReleaseCurrent();
    }
  } release{impl_->owned_context.get()};
  return impl_->Run(this, job, capture);
}

// ---------------------------------------------------------------------------------------------
// Run's stages.

namespace {

// The stage times of SweepStats, in GPU time: with `enabled` (GlslSweepKernelOptions::
// time_stages) each boundary is a GPU timestamp (glQueryCounter), read once the job is done
// (Resolve). Nothing waits between stages, so the GPU never idles for the timing.
class StageClock {
 public:
  explicit StageClock(bool enabled) : enabled_(enabled) {}
  ~StageClock() {
    if (!queries_.empty()) glDeleteQueries(static_cast<GLsizei>(queries_.size()), queries_.data());
  }
  StageClock(const StageClock&) = delete;
  StageClock& operator=(const StageClock&) = delete;

  // The CPU time since the start (preparation and uploads); the first stage starts now.
  double Prepared() {
    Mark(nullptr);
    return total_.Seconds();
  }
  // The GPU time since the last boundary goes to `*stage_seconds`.
  void Book(double* stage_seconds) { Mark(stage_seconds); }
  // Leaves the time since the last boundary out of every stage (a capture's read-backs).
  void Skip() { Mark(nullptr); }
  // Adds the intervals to their stages; waits for the GPU's last boundary.
  void Resolve() {
    GLuint64 last = 0;
    for (size_t i = 0; i < queries_.size(); ++i) {
      GLuint64 now = 0;
      glGetQueryObjectui64v(queries_[i], GL_QUERY_RESULT, &now);
      if (i > 0 && stages_[i] != nullptr) *stages_[i] += 1e-9 * static_cast<double>(now - last);
      last = now;
    }
  }
  double Total() const { return total_.Seconds(); }

 private:
  void Mark(double* stage_seconds) {
    if (!enabled_) return;
    GLuint query = 0;
    glGenQueries(1, &query);
    glQueryCounter(query, GL_TIMESTAMP);
    queries_.push_back(query);
    stages_.push_back(stage_seconds);
  }

  bool enabled_;
  Timer total_;
  std::vector<GLuint> queries_;
  std::vector<double*> stages_;
};

// The tile records every batch reduces into (see sweep_tile_best.comp): per tile its column and
// row range, best NCC (the threshold until one beats it), winner (offset, neighbour, pixel,
// face), world position and the other neighbours that matched; per batch two counters (defined
// NCCs, covered pixels).
struct TileRecords {
  TileRecords(const TileGrid& tiles, float threshold, int match_words, int num_batches);
  gl::Buffer columns, rows, best_ncc, best_info, best_position, best_matched, counters;
};

// begin(t) for t = 0..count (the last one: the image's size).
template <typename Begin>
std::vector<int32_t> TileBegins(int count, Begin begin) {
  std::vector<int32_t> begins(count + 1);
  for (int t = 0; t <= count; ++t) begins[t] = begin(t);
  return begins;
}

TileRecords::TileRecords(const TileGrid& tiles, float threshold, int match_words, int num_batches)
    : columns(gl::Buffer::FromVector(
          TileBegins(tiles.tiles_x, [&tiles](int t) { return tiles.XBegin(t); }))),
      rows(gl::Buffer::FromVector(
          TileBegins(tiles.tiles_y, [&tiles](int t) { return tiles.YBegin(t); }))),
      best_ncc(gl::Buffer::FromVector(std::vector<float>(tiles.NumTiles(), threshold))),
      best_info(
          gl::Buffer::FromVector(std::vector<Eigen::Vector4i>(tiles.NumTiles(), {0, -1, 0, -1}))),
      best_position(gl::Buffer::FromVector(
          std::vector<Eigen::Vector4f>(tiles.NumTiles(), Eigen::Vector4f::Zero()))),
      best_matched(gl::Buffer::FromVector(
          std::vector<uint32_t>(size_t{1} * tiles.NumTiles() * match_words, 0))),
      counters(gl::Buffer::FromVector(std::vector<uint32_t>(2 * size_t{1} * num_batches, 0))) {}

}  // namespace

// The offsets of one batch: layer b of every texture array sweeps k = first_offset + b.
struct GlslSweepKernel::Impl::Batch {
  // The offsets in batches of at most `size`, in increasing k. Where rule.must_move, k = 0 comes
  // first, alone, as the unswept batch, and the others' batches skip it.
  static std::vector<Batch> Split(const PreparedSweep& prep, const WinnerRule& rule, int size);
  int index = 0;
  int layers = 0;
  int first_offset = 0;  // k of layer 0
  bool unswept = false;  // the NCC maps at k = 0 that the others must beat; competes for nothing
};

// One reprojection dispatch per group of neighbours (image units are limited). Groups of the
// same size share a program: GpuJob::SetGroup sets its uniforms before each dispatch.
struct GlslSweepKernel::Impl::Group {
  int first, count;
  gl::ShaderProgram* program;
};

// A job on the GPU (UploadJob): its mesh, images and tile records, and what the passes of every
// batch need.
struct GlslSweepKernel::Impl::GpuJob {
  // Uploads the mesh, the images and the tile records; `batch_size` offsets per batch.
  GpuJob(const SweepJob& job, const PreparedSweep& prep, const WinnerRule& rule, int batch_size,
         bool clip_control);
  // The uniforms of a raster program sweeping the mesh as seen from `view` (C or a neighbour).
  void SetSweep(const gl::ShaderProgram& program, const View& view, double far) const;
  // Those of the world + reprojection pass for a group of neighbours.
  void SetGroup(const Group& group) const;

  const SweepJob& job;
  const PreparedSweep& prep;
  const int width, height, num_neighbours, radius, match_words;
  const std::vector<Batch> batches;
  BlurPrograms* blur = nullptr;
  gl::ShaderProgram* tile_best = nullptr;
  // Dispatch sizes of the row-sum and column-sum + NCC passes.
  int rows_groups_x = 0, rows_groups_y = 0, ncc_groups_x = 0, ncc_groups_y = 0;

  const gl::GpuMesh mesh;
  const Eigen::Vector3d origin;  // of the mesh's float coordinates
  const gl::Texture2D image;     // C's
  std::vector<gl::Texture2D> neighbour_images;
  const TileRecords records;

  // Rendering state.
  const bool clip_control;  // reversed-Z depth
  const gl::DepthRange range;
  const float clear_depth;
  const Eigen::Vector3f center;  // C's, relative to origin
  double far_c = 0;              // far planes of C's and the neighbours' views
  std::vector<double> far_n;
  std::vector<Group> groups;
};

std::vector<GlslSweepKernel::Impl::Batch> GlslSweepKernel::Impl::Batch::Split(
    const PreparedSweep& prep, const WinnerRule& rule, int size) {
  std::vector<Batch> batches;
  const auto add = [&](int first_offset, int layers, bool unswept) {
    Batch batch;
    batch.index = static_cast<int>(batches.size());
    batch.layers = layers;
    batch.first_offset = first_offset;
    batch.unswept = unswept;
    batches.push_back(batch);
  };
  if (rule.must_move) add(0, 1, true);
  // Runs of consecutive offsets (a layer's k is first_offset + layer), each in batches.
  const std::vector<int> competing = CompetingOffsets(prep, rule);
  for (size_t run = 0; run < competing.size();) {
    size_t end = run + 1;
    while (end < competing.size() && competing[end] == competing[end - 1] + 1) ++end;
    for (size_t first = run; first < end; first += size) {
      add(competing[first], static_cast<int>(std::min<size_t>(size, end - first)), false);
    }
    run = end;
  }
  return batches;
}

GlslSweepKernel::Impl::GpuJob::GpuJob(const SweepJob& job, const PreparedSweep& prep,
                                      const WinnerRule& rule, int batch_size, bool clip_control)
    : job(job),
      prep(prep),
      width(prep.camera.view.intrinsics.width),
      height(prep.camera.view.intrinsics.height),
      num_neighbours(static_cast<int>(prep.neighbours.size())),
      radius((prep.window.rows - 1) / 2),
      match_words(gl::DivideRoundingUp(num_neighbours, 32)),
      batches(Batch::Split(prep, rule, batch_size)),
      mesh(job.mesh),
      origin(mesh.origin()),
      image(gl::Texture2D::FromImage(prep.camera.image, gl::TextureFormat::kR32F)),
      records(prep.tiles, static_cast<float>(job.options.ncc_threshold), match_words,
              static_cast<int>(batches.size())),
      clip_control(clip_control),
      range(clip_control ? gl::DepthRange::kReversedZeroToOne : gl::DepthRange::kNegativeOneToOne),
      clear_depth(clip_control ? 0.0f : 1.0f),
      center((prep.camera.view.Center() - origin).cast<float>()) {
  for (const SweepCamera& n : prep.neighbours)
    neighbour_images.push_back(gl::Texture2D::FromImage(n.image, gl::TextureFormat::kR32F));
  // Far planes beyond every swept vertex.
  const int max_offset = std::max(std::abs(prep.offsets.front()), std::abs(prep.offsets.back()));
  const double max_shift = std::abs(prep.alpha) * max_offset;
  far_c = FarPlane(prep.camera.view, job.mesh, max_shift);
  for (const SweepCamera& n : prep.neighbours) {
    far_n.push_back(FarPlane(n.view, job.mesh, max_shift));
  }
}

void GlslSweepKernel::Impl::GpuJob::SetSweep(const gl::ShaderProgram& program, const View& view,
                                             double far) const {
  program.Set("u_center", center);
  program.Set("u_alpha", static_cast<float>(prep.alpha));
  program.Set("u_model_view", gl::ModelView(view, origin).cast<float>().eval());
  program.Set("u_projection",
              gl::GlProjection(view.intrinsics, prep.near, far, range).cast<float>().eval());
}

void GlslSweepKernel::Impl::GpuJob::SetGroup(const Group& group) const {
  const gl::ShaderProgram& p = *group.program;
  const View& c = prep.camera.view;
  const Intrinsics& k = c.intrinsics;
  Eigen::Matrix3d k_inverse;
  k_inverse << 1 / k.fx, 0, -k.cx / k.fx, 0, 1 / k.fy, -k.cy / k.fy, 0, 0, 1;
  p.Set("u_pixel_offset", radius);
  p.Set("u_image_width", width);
  p.Set("u_center", center);
  p.Set("u_pixel_to_ray", (c.R.transpose() * k_inverse).cast<float>().eval());
  p.Set("u_write_world", group.first == 0 ? 1 : 0);
  p.Set("u_occlusion", static_cast<float>(1 + job.options.occlusion_tolerance));
  for (int i = 0; i < group.count; ++i) {
    const View& n = prep.neighbours[group.first + i].view;
    p.Set(fmt::format("u_neighbour_size[{}]", i),
          Eigen::Vector2i(n.intrinsics.width, n.intrinsics.height));
    p.Set(fmt::format("u_rotation[{}]", i), n.R.cast<float>().eval());
    p.Set(fmt::format("u_translation[{}]", i), (n.R * origin + n.t).cast<float>().eval());
    p.Set(fmt::format("u_intrinsics[{}]", i),
          Eigen::Vector4f(n.intrinsics.fx, n.intrinsics.fy, n.intrinsics.cx, n.intrinsics.cy));
  }
}

// Copies the images of GlslSweepCapture::offset out of the batch that sweeps it, at the stage
// boundaries Run calls it at; does nothing without a capture. Returns whether it read anything
// back (that time belongs to no stage).
class GlslSweepKernel::Impl::CaptureRecorder {
 public:
  CaptureRecorder(GlslSweepCapture* capture, const GpuJob& gpu, const Resources& resources)
      : capture_(capture), gpu_(gpu), resources_(resources) {}
  // After RenderCameraView: C's world position, depth and face; per neighbour the shadow map,
  // the reprojection and its mask.
  bool AfterRender(const Batch& batch);
  // After NccBatch: the NCC maps.
  bool AfterNcc(const Batch& batch);

 private:
  // The captured offset's layer in `batch`, -1 if the batch does not sweep it.
  int Layer(const Batch& batch) const {
    if (capture_ == nullptr) return -1;
    const int layer = capture_->offset - batch.first_offset;
    return layer >= 0 && layer < batch.layers ? layer : -1;
  }

  GlslSweepCapture* capture_;
  const GpuJob& gpu_;
  const Resources& resources_;
};

bool GlslSweepKernel::Impl::CaptureRecorder::AfterRender(const Batch& batch) {
  const int layer = Layer(batch);
  if (layer < 0) return false;
  const int width = gpu_.width, height = gpu_.height, radius = gpu_.radius;
  const Eigen::Vector3d& origin = gpu_.origin;
  const View& view = gpu_.prep.camera.view;
  const cv::Mat world4 = resources_.world->DownloadLayer(layer).colRange(radius, radius + width);
  capture_->world.create(height, width, CV_32FC3);
  capture_->depth.create(height, width, CV_32F);
  capture_->face.create(height, width, CV_32S);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const cv::Vec4f w = world4.at<cv::Vec4f>(r, c);
      const bool covered = w[3] >= 0;
      const Eigen::Vector3d x(w[0], w[1], w[2]);
      capture_->depth.at<float>(r, c) = covered ? static_cast<float>(view.ToCamera(x + origin).z())
                                                : std::numeric_limits<float>::infinity();
      capture_->face.at<int32_t>(r, c) = covered ? static_cast<int32_t>(w[3]) : -1;
      capture_->world.at<cv::Vec3f>(r, c) = covered
                                                ? cv::Vec3f(static_cast<float>(w[0] + origin.x()),
                                                            static_cast<float>(w[1] + origin.y()),
                                                            static_cast<float>(w[2] + origin.z()))
                                                : cv::Vec3f(0, 0, 0);
    }
  }
  capture_->shadow.clear();
  capture_->reprojected.clear();
  capture_->mask.clear();
  for (int j = 0; j < gpu_.num_neighbours; ++j) {
    capture_->shadow.push_back(resources_.shadow[j]->DownloadLayer(layer));
    const cv::Mat reprojected =
        resources_.reprojected[j]->DownloadLayer(layer).colRange(radius, radius + width);
    cv::Mat values(height, width, CV_32F, cv::Scalar(0));
    cv::Mat mask(height, width, CV_8U, cv::Scalar(0));
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) {
        const cv::Vec4f v = reprojected.at<cv::Vec4f>(r, c);
        if (v[0] > 0) {
          mask.at<uint8_t>(r, c) = 255;
          values.at<float>(r, c) = v[3];
        }
      }
    }
    capture_->reprojected.push_back(values);
    capture_->mask.push_back(mask);
  }
  return true;
}

bool GlslSweepKernel::Impl::CaptureRecorder::AfterNcc(const Batch& batch) {
  const int layer = Layer(batch);
  if (layer < 0) return false;
  capture_->ncc.clear();
  for (int j = 0; j < gpu_.num_neighbours; ++j) {
    cv::Mat ncc = resources_.ncc->DownloadLayer(layer * gpu_.num_neighbours + j);
    ncc.setTo(std::numeric_limits<float>::quiet_NaN(), ncc < -1.5f);
    capture_->ncc.push_back(ncc);
  }
  return true;
}

SweepResult GlslSweepKernel::Impl::Run(GlslSweepKernel* kernel, const SweepJob& job,
                                       GlslSweepCapture* capture) {
  StageClock clock(options.time_stages);
  const PreparedSweep prep = PrepareSweep(job);
  CheckLimits(job, prep, capture);
  if (!context->IsCurrent()) context->MakeCurrent();
  SweepResult result;
  result.stats = PreparedSweepStats(prep);
  SweepStats& stats = result.stats;
  const WinnerRule rule = WinnerRule::For(job.options, static_cast<int>(prep.neighbours.size()));
  const std::unique_ptr<GpuJob> gpu = UploadJob(job, prep, rule, kernel->PlanMemory(prep, rule));
  CaptureRecorder recorder(capture, *gpu, resources);
  stats.prepare_s = clock.Prepared();
  for (const Batch& batch : gpu->batches) {
    RenderShadowMaps(*gpu, batch);
    clock.Book(&stats.raster_s);
    RenderCameraView(*gpu, batch);
    clock.Book(&stats.reproject_s);
    if (recorder.AfterRender(batch)) clock.Skip();
    NccBatch(*gpu, batch);
    if (batch.unswept) KeepUnsweptNcc(*gpu);
    clock.Book(&stats.ncc_s);
    if (recorder.AfterNcc(batch)) clock.Skip();
    ReduceBatch(*gpu, batch);
    clock.Book(&stats.reduce_s);
  }
  result.points = ReadBackWinners(*gpu, &stats);
  clock.Resolve();
  stats.total_s = clock.Total();
  return result;
}

// The kernel's limits (2^24 faces, the driver's texture size with the blur padding) and the
// capture's offset.
void GlslSweepKernel::Impl::CheckLimits(const SweepJob& job, const PreparedSweep& prep,
                                        const GlslSweepCapture* capture) const {
  const std::string name = fmt::format("sweep job for camera {}", job.camera.id);
  if (static_cast<int64_t>(job.mesh.faces.size()) >= kMaxFaces) {
    throw InputError(fmt::format("{}: {} faces; the GLSL kernel takes fewer than {}", name,
                                 job.mesh.faces.size(), kMaxFaces));
  }
  const int width = prep.camera.view.intrinsics.width;
  const int height = prep.camera.view.intrinsics.height;
  const int radius = (prep.window.rows - 1) / 2;
  int64_t longest = std::max<int64_t>(PaddedWidth(width, radius), height + 2 * radius + block);
  for (const SweepCamera& n : prep.neighbours) {
    longest =
        std::max<int64_t>(longest, std::max(n.view.intrinsics.width, n.view.intrinsics.height));
  }
  const gl::GlInfo& info = context->info();
  if (info.max_texture_size > 0 && longest > info.max_texture_size) {
    throw InputError(fmt::format(
        "{}: images of {}x{} (swept resolution, plus {} px of blur padding) exceed the GL "
        "driver's texture size limit of {}; lower --sweep.max-image-dimension",
        name, width, height, 2 * radius + block, info.max_texture_size));
  }
  if (capture != nullptr &&
      std::find(prep.offsets.begin(), prep.offsets.end(), capture->offset) == prep.offsets.end()) {
    throw InputError(fmt::format("{}: capture of offset {}, which the job does not sweep", name,
                                 capture->offset));
  }
}

// Gets the programs and textures of the job's shape, puts the job on the GPU (GpuJob) in batches
// of plan.offsets_per_batch, groups the neighbours for C's draws, and sets the compute passes'
// uniforms that stay for the whole job.
std::unique_ptr<GlslSweepKernel::Impl::GpuJob> GlslSweepKernel::Impl::UploadJob(
    const SweepJob& job, const PreparedSweep& prep, const WinnerRule& rule,
    const MemoryPlan& plan) {
  const int radius = (prep.window.rows - 1) / 2;
  BlurPrograms& programs = Blur(radius);
  Allocate(prep, plan.offsets_per_batch, radius, rule.must_move);
  auto gpu = std::make_unique<GpuJob>(job, prep, rule, plan.offsets_per_batch,
                                      context->info().clip_control);
  gl::ShaderProgram& tile_best = TileBest(radius, gpu->match_words);
  gpu->blur = &programs;
  gpu->tile_best = &tile_best;
  const int num_neighbours = gpu->num_neighbours;
  for (int first = 0; first < num_neighbours; first += max_group) {
    const int count = std::min(max_group, num_neighbours - first);
    gpu->groups.push_back({first, count, &Reproject(count)});
  }

  const int width = gpu->width, height = gpu->height;
  const SweepOptions& sweep = job.options;
  const std::vector<float> weights(prep.window.begin<float>(), prep.window.end<float>());
  programs.rows.Set("u_size", Eigen::Vector2i(width, height));
  programs.rows.Set("u_weights", weights);
  programs.ncc.Set("u_size", Eigen::Vector2i(width, height));
  programs.ncc.Set("u_weights", weights);
  programs.ncc.SetDouble("u_min_window_weight", sweep.min_window_weight);
  programs.ncc.SetDouble("u_min_texture_variance", sweep.min_texture_variance);
  tile_best.Set("u_neighbours", num_neighbours);
  tile_best.Set("u_width", width);
  tile_best.Set("u_threshold", rule.threshold);
  tile_best.Set("u_required", rule.required_matches);
  tile_best.Set("u_support", rule.support);
  tile_best.Set("u_strict", rule.strict ? 1 : 0);
  tile_best.Set("u_must_move", rule.must_move ? 1 : 0);
  gl::CheckGlError("sweep setup");
  const bool transposed = variant == GlslBlurVariant::kUnrolled;
  gpu->rows_groups_x = gl::DivideRoundingUp(gl::DivideRoundingUp(width, block), local_x);
  gpu->rows_groups_y = gl::DivideRoundingUp(height, local_y);
  gpu->ncc_groups_x =
      gl::DivideRoundingUp(transposed ? gl::DivideRoundingUp(height, block) : width, local_x);
  gpu->ncc_groups_y =
      gl::DivideRoundingUp(transposed ? width : gl::DivideRoundingUp(height, block), local_y);
  if (Tiled(radius)) {
    const Eigen::Vector2i tile = NccTile(radius);
    gpu->ncc_groups_x = gl::DivideRoundingUp(width, tile.x());
    gpu->ncc_groups_y = gl::DivideRoundingUp(height, tile.y());
  }
  return gpu;
}

namespace {

// Depth-tested drawing of the swept meshes (reversed Z with clip control).
void BeginSweepRaster(bool clip_control) {
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  if (clip_control) {
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glDepthFunc(GL_GREATER);
  } else {
    glDepthFunc(GL_LESS);
  }
}

void EndSweepRaster(bool clip_control, const char* what) {
  if (clip_control) glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  gl::CheckGlError(what);
}

}  // namespace

// Every swept mesh of the batch seen from each neighbour: its camera z (one instanced draw per
// neighbour, one layer per offset).
void GlslSweepKernel::Impl::RenderShadowMaps(const GpuJob& gpu, const Batch& batch) {
  BeginSweepRaster(gpu.clip_control);
  gpu.mesh.vertex_array().Bind();
  const GLsizei index_count = static_cast<GLsizei>(3 * gpu.mesh.num_faces());
  const float infinity = std::numeric_limits<float>::infinity();
  for (int j = 0; j < gpu.num_neighbours; ++j) {
    const SweepCamera& n = gpu.prep.neighbours[j];
    resources.shadow_targets[j]->BindAndClear(
        {Eigen::Vector4f(infinity, 0, 0, 0)}, gpu.clear_depth,
        cv::Rect(0, 0, n.view.intrinsics.width, n.view.intrinsics.height));
    if (!(gpu.far_n[j] > gpu.prep.near)) continue;
    gpu.SetSweep(*raster_depth, n.view, gpu.far_n[j]);
    raster_depth->Set("u_first_offset", batch.first_offset);
    raster_depth->Use();
    glDrawElementsInstanced(GL_TRIANGLES, index_count, GL_UNSIGNED_INT, nullptr, batch.layers);
  }
  EndSweepRaster(gpu.clip_control, "sweep shadow maps");
}

// Every swept mesh of the batch seen from C: camera z and face of the surface it sees; then per
// pixel its world position and each neighbour's image reprojected through it (one dispatch
// per group of neighbours).
void GlslSweepKernel::Impl::RenderCameraView(const GpuJob& gpu, const Batch& batch) {
  BeginSweepRaster(gpu.clip_control);
  gpu.mesh.vertex_array().Bind();
  const GLsizei index_count = static_cast<GLsizei>(3 * gpu.mesh.num_faces());
  resources.surface_target->BindAndClear({Eigen::Vector4f(0, -1, 0, 0)}, gpu.clear_depth,
                                         cv::Rect(gpu.radius, 0, gpu.width, gpu.height));
  if (gpu.far_c > gpu.prep.near) {
    gpu.SetSweep(*raster_surface, gpu.prep.camera.view, gpu.far_c);
    raster_surface->Set("u_first_offset", batch.first_offset);
    raster_surface->Use();
    glDrawElementsInstanced(GL_TRIANGLES, index_count, GL_UNSIGNED_INT, nullptr, batch.layers);
  }
  EndSweepRaster(gpu.clip_control, "sweep rasterization");
  gl::MemoryBarrier();

  const int padded = PaddedWidth(gpu.width, gpu.radius);
  gpu.image.Bind(0);
  for (const Group& group : gpu.groups) {
    for (int i = 0; i < group.count; ++i) {
      gpu.neighbour_images[group.first + i].Bind(1 + i);
      resources.shadow[group.first + i]->Bind(1 + group.count + i);
      resources.reprojected[group.first + i]->BindImage(1 + i, gl::ImageAccess::kWriteOnly);
    }
    resources.surface->Bind(1 + 2 * group.count);
    resources.world->BindImage(0, gl::ImageAccess::kWriteOnly);
    gpu.SetGroup(group);
    group.program->Set("u_size", Eigen::Vector2i(padded, gpu.height));
    group.program->Set("u_layers", batch.layers);
    group.program->Dispatch(gl::DivideRoundingUp(padded, 8), gl::DivideRoundingUp(gpu.height, 8),
                            batch.layers);
  }
  gl::MemoryBarrier();
  gl::CheckGlError("sweep world + reprojection");
}

// Per offset and neighbour: the row sums, then the column sums and the NCC.
void GlslSweepKernel::Impl::NccBatch(const GpuJob& gpu, const Batch& batch) {
  const BlurPrograms& programs = *gpu.blur;
  for (int b = 0; b < batch.layers; ++b) {
    for (int j = 0; j < gpu.num_neighbours; ++j) {
      resources.reprojected[j]->BindImage(2, gl::ImageAccess::kReadOnly);
      resources.sums0->BindImage(0, gl::ImageAccess::kWriteOnly);
      resources.sums1->BindImage(1, gl::ImageAccess::kWriteOnly);
      programs.rows.Set("u_layer", b);
      programs.rows.Dispatch(gpu.rows_groups_x, gpu.rows_groups_y);
      gl::MemoryBarrier();

      resources.sums0->BindImage(1, gl::ImageAccess::kReadOnly);
      resources.sums1->BindImage(2, gl::ImageAccess::kReadOnly);
      resources.reprojected[j]->BindImage(3, gl::ImageAccess::kReadOnly);
      resources.ncc->BindImage(0, gl::ImageAccess::kWriteOnly);
      programs.ncc.Set("u_layer", b);
      programs.ncc.Set("u_ncc_layer", b * gpu.num_neighbours + j);
      programs.ncc.Dispatch(gpu.ncc_groups_x, gpu.ncc_groups_y);
      gl::MemoryBarrier();
    }
  }
  gl::CheckGlError("sweep NCC");
}

// The unswept batch's NCC maps (layers 0..neighbours-1) kept for the batches after it.
void GlslSweepKernel::Impl::KeepUnsweptNcc(const GpuJob& gpu) {
  glCopyImageSubData(resources.ncc->id(), GL_TEXTURE_2D_ARRAY, 0, 0, 0, 0,
                     resources.unswept_ncc->id(), GL_TEXTURE_2D_ARRAY, 0, 0, 0, 0, gpu.width,
                     gpu.height, gpu.num_neighbours);
  gl::MemoryBarrier();
  gl::CheckGlError("sweep NCC at k = 0");
}

// Every tile's best pixel of the batch against its record so far (one work group per tile);
// the unswept batch only counts.
void GlslSweepKernel::Impl::ReduceBatch(const GpuJob& gpu, const Batch& batch) {
  const TileRecords& records = gpu.records;
  resources.ncc->BindImage(0, gl::ImageAccess::kReadOnly);
  resources.world->BindImage(1, gl::ImageAccess::kReadOnly);
  // Read only where winners must move; some array is bound there either way.
  (resources.unswept_ncc ? *resources.unswept_ncc : *resources.ncc)
      .BindImage(2, gl::ImageAccess::kReadOnly);
  records.columns.BindStorage(0);
  records.rows.BindStorage(1);
  records.best_ncc.BindStorage(2);
  records.best_info.BindStorage(3);
  records.best_position.BindStorage(4);
  records.best_matched.BindStorage(5);
  records.counters.BindStorage(6);
  gl::ShaderProgram& tile_best = *gpu.tile_best;
  tile_best.Set("u_layers", batch.layers);
  tile_best.Set("u_first_offset", batch.first_offset);
  tile_best.Set("u_batch", batch.index);
  tile_best.Set("u_compete", batch.unswept ? 0 : 1);
  tile_best.Dispatch(gpu.prep.tiles.tiles_x, gpu.prep.tiles.tiles_y);
  gl::MemoryBarrier();
  gl::CheckGlError("sweep tile-best");
}

// The tile records as points (MakeSweepPoint), and the batches' counters into `stats`.
std::vector<SweepPoint> GlslSweepKernel::Impl::ReadBackWinners(const GpuJob& gpu,
                                                               SweepStats* stats) const {
  const TileRecords& records = gpu.records;
  const int num_tiles = gpu.prep.tiles.NumTiles();
  const int num_batches = static_cast<int>(gpu.batches.size());
  const size_t match_words = gpu.match_words;
  const std::vector<float> ncc = records.best_ncc.DownloadVector<float>(num_tiles);
  const std::vector<Eigen::Vector4i> winners =
      records.best_info.DownloadVector<Eigen::Vector4i>(num_tiles);
  const std::vector<Eigen::Vector4f> positions =
      records.best_position.DownloadVector<Eigen::Vector4f>(num_tiles);
  const std::vector<uint32_t> matched =
      records.best_matched.DownloadVector<uint32_t>(num_tiles * match_words);
  const std::vector<uint32_t> counts =
      records.counters.DownloadVector<uint32_t>(2 * size_t{1} * num_batches);
  for (int batch = 0; batch < num_batches; ++batch) {
    stats->valid_hypotheses += counts[2 * batch];
    stats->covered_pixels += counts[2 * batch + 1];
  }
  std::vector<SweepPoint> points;
  for (int t = 0; t < num_tiles; ++t) {
    const Eigen::Vector4i& w = winners[t];  // offset, neighbour (-1: none), pixel index, face
    if (w[1] < 0) continue;
    TileWinner winner;
    winner.ncc = ncc[t];
    winner.offset = w[0];
    winner.neighbour = w[1];
    winner.col = w[2] % gpu.width;
    winner.row = w[2] / gpu.width;
    winner.face = w[3];
    winner.position = gpu.origin + positions[t].head<3>().cast<double>();
    for (int other = 0; other < gpu.num_neighbours; ++other) {
      if (matched[t * match_words + other / 32] & (1u << (other % 32))) {
        winner.matched.push_back(other);
      }
    }
    points.push_back(MakeSweepPoint(winner, gpu.prep));
  }
  return points;
}

}  // namespace ms
