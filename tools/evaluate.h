// Depth-map accuracy of a mesh against a ground-truth mesh, as in the paper (section 3, after
// Strecha et al. 2008): render both from a camera; on pixels where the ground truth has a
// surface, compare depths. All functions take in-memory data; `manisweep evaluate` reads files.
//
// Definitions, over the pixels of the evaluated views where the ground truth is valid (G) and
// the subset where the mesh has a surface too (C):
//   MAE = mean_C |d - d*|, MRE = mean_C |d - d*| / d*, RMS = sqrt(mean_C (d - d*)^2),
//   coverage = |C| / |G|, cumulative[m-1] = |{p in C : |d - d*| < m Sigma}| / |G|, m = 1..M
// (pixels the mesh misses count as failures in the cumulative share, so the curve ends at or
// below the coverage), and the coverage-complete
//   MAE_all = (sum_C |d - d*| + |G \ C| M Sigma) / |G|:
// a pixel the mesh misses counts as an error of M Sigma, the end of the cumulative curve (so a
// mesh cannot look better by leaving out its hardest pixels; equal to MAE at full coverage). Depth
// d = camera z by default, or the distance from the camera centre (DepthMeasure::kRange). Sigma
// defaults to median(d* over G) / 20, which is close to the paper's 0.06 m at the ~1.2 m viewing
// distance of its synthetic scenes; give it explicitly
// (--sigma 0.06) to compare with the paper's figures.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "gl/context.h"
#include "mesh/mesh.h"
#include "scene/scene.h"

namespace ms {

enum class DepthMeasure {
  kCameraZ,  // z in camera coordinates (what depth maps hold)
  kRange,    // Euclidean distance from the camera centre along the pixel's ray
};
DepthMeasure ParseDepthMeasure(const std::string& name);  // "z" or "range"
std::string DepthMeasureName(DepthMeasure measure);

struct EvaluateOptions {
  std::vector<int> views;  // views to render from; empty: {0} (the paper's "first camera")
  bool all_views = false;  // every view of the scene (overrides `views`)
  double sigma = 0;        // Sigma of the cumulative curve; 0: median ground-truth depth / 20
  DepthMeasure measure = DepthMeasure::kCameraZ;  // what d and d* are
  int max_multiple = 10;                          // cumulative shares for m = 1..max_multiple
  void Check() const;                             // throws InputError naming the field
};

constexpr double kSigmaDepthRatio = 20;  // Sigma = median depth / this when not given

struct DepthErrorStats {
  int64_t gt_pixels = 0;       // |G|
  int64_t covered_pixels = 0;  // |C|
  double mae = 0, mre = 0, rms = 0, coverage = 0;
  double mae_all = 0;              // over G, a missed pixel counting missing_penalty
  double missing_penalty = 0;      // max_multiple x Sigma
  std::vector<double> cumulative;  // share of G with error < m Sigma, m = 1..max_multiple
};

// Sums that combine over views; Finish turns them into DepthErrorStats.
class DepthErrorAccumulator {
 public:
  explicit DepthErrorAccumulator(double sigma, int max_multiple = 10);
  // depth, gt: CV_32F of equal size, > 0 where a surface was rendered.
  void Add(const cv::Mat& depth, const cv::Mat& gt);
  DepthErrorStats Finish() const;

 private:
  double sigma_;
  int max_multiple_;
  int64_t gt_pixels_ = 0;
  int64_t covered_ = 0;
  double sum_abs_ = 0, sum_rel_ = 0, sum_sq_ = 0;
  std::vector<int64_t> within_;  // within_[m-1]: errors in [(m-1) Sigma, m Sigma)
};

// Camera-z depth map -> distance from the camera centre (pixel centres at +0.5; 0 stays 0).
cv::Mat RangeFromDepth(const cv::Mat& depth, const Intrinsics& intrinsics);

// One comparison: d vs d* from one view (no GL).
DepthErrorStats CompareDepthMaps(const cv::Mat& depth, const cv::Mat& gt, double sigma,
                                 int max_multiple = 10);

struct ViewEvaluation {
  int view = 0;
  std::string view_name;
  DepthErrorStats stats;
};

struct MeshEvaluation {
  std::string label;                  // file name or caller's label
  std::vector<ViewEvaluation> views;  // per evaluated view
  DepthErrorStats total;              // pooled over the pixels of all evaluated views
  cv::Mat first_depth;                // depth map of the first evaluated view (error images)
};

struct Evaluation {
  std::vector<int> views;  // evaluated view indices
  double sigma = 0;
  std::string sigma_rule;  // "given" or "median ground-truth depth / 20 = ..."
  DepthMeasure measure = DepthMeasure::kCameraZ;
  double median_gt_depth = 0;  // over G (0 when Sigma was given and there are > 8 views)
  cv::Mat first_gt_depth;      // ground-truth depth of the first evaluated view
  std::vector<MeshEvaluation> meshes;
};

struct LabeledMesh {
  std::string label;
  const Mesh* mesh = nullptr;
};

// Renders the ground truth and every mesh from the chosen views of `scene` and compares.
// Throws InputError for a view index out of range, or when the ground truth covers no pixel.
Evaluation EvaluateMeshes(const gl::GlContext& context, const std::vector<LabeledMesh>& meshes,
                          const Mesh& ground_truth, const Scene& scene,
                          const EvaluateOptions& options);

// Files `manisweep evaluate` writes; empty paths are skipped. Each is written atomically.
struct EvaluationFiles {
  std::string json;         // EvaluationToJson (+ ground_truth and scene names below)
  std::string error_image;  // ErrorFigure of the first evaluated view, one panel per mesh
  std::string plot;         // CumulativePlot, one curve per mesh (pooled over views)
  double error_max = 0;     // top of the error colour scale; 0: 5 Sigma
  std::string ground_truth_name, scene_name;  // recorded in the JSON
};
void WriteEvaluationFiles(const Evaluation& evaluation, const EvaluationFiles& files);

// Human-readable table (one row per mesh, pooled over views; per-view rows when several views).
std::string FormatEvaluationTable(const Evaluation& evaluation);
nlohmann::json EvaluationToJson(const Evaluation& evaluation);

}  // namespace ms
