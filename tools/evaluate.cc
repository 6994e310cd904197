#include "tools/evaluate.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "gl/mesh_renderer.h"
#include "tools/plot.h"

namespace ms {

DepthMeasure ParseDepthMeasure(const std::string& name) {
  if (name == "z") return DepthMeasure::kCameraZ;
  if (name == "range") return DepthMeasure::kRange;
  throw InputError("--depth: unknown depth measure '" + name + "' (use z or range)");
}

std::string DepthMeasureName(DepthMeasure measure) {
  return measure == DepthMeasure::kRange ? "range" : "z";
}

cv::Mat RangeFromDepth(const cv::Mat& depth, const Intrinsics& k) {
  cv::Mat range(depth.size(), CV_32F);
  for (int r = 0; r < depth.rows; ++r) {
    const double b = (r + 0.5 - k.cy) / k.fy;
    for (int c = 0; c < depth.cols; ++c) {
      const double a = (c + 0.5 - k.cx) / k.fx;
      range.at<float>(r, c) =
          static_cast<float>(depth.at<float>(r, c) * std::sqrt(a * a + b * b + 1));
    }
  }
  return range;
}

void EvaluateOptions::Check() const {
  for (int v : views) {
    if (v < 0) throw InputError(fmt::format("evaluate.views: view index {} is negative", v));
  }
  if (!(sigma >= 0) || !std::isfinite(sigma)) throw InputError("evaluate.sigma: must be >= 0");
  if (max_multiple < 1 || max_multiple > 1000) {
    throw InputError("evaluate.max_multiple: must be in [1, 1000]");
  }
}

DepthErrorAccumulator::DepthErrorAccumulator(double sigma, int max_multiple)
    : sigma_(sigma), max_multiple_(max_multiple), within_(max_multiple, 0) {}

void DepthErrorAccumulator::Add(const cv::Mat& depth, const cv::Mat& gt) {
  if (depth.type() != CV_32F || gt.type() != CV_32F || depth.size() != gt.size()) {
    throw InternalError("DepthErrorAccumulator: depth maps must be CV_32F of equal size");
  }
  for (int r = 0; r < gt.rows; ++r) {
    const float* d_row = depth.ptr<float>(r);
    const float* g_row = gt.ptr<float>(r);
    for (int c = 0; c < gt.cols; ++c) {
      const double g = g_row[c];
      if (!(g > 0)) continue;
      ++gt_pixels_;
      const double d = d_row[c];
      if (!(d > 0)) continue;
      const double error = std::abs(d - g);
      sum_abs_ += error;
      sum_rel_ += error / g;
      sum_sq_ += error * error;
      ++covered_;
      // error < m * sigma  <=>  m > error / sigma: the first m that counts it.
      const double first = std::floor(error / sigma_) + 1;
      if (first <= max_multiple_) ++within_[static_cast<int>(first) - 1];
    }
  }
}

DepthErrorStats DepthErrorAccumulator::Finish() const {
  DepthErrorStats s;
  s.gt_pixels = gt_pixels_;
  s.covered_pixels = covered_;
  if (covered_ > 0) {
    s.mae = sum_abs_ / covered_;
    s.mre = sum_rel_ / covered_;
    s.rms = std::sqrt(sum_sq_ / covered_);
  }
  s.coverage = gt_pixels_ > 0 ? static_cast<double>(covered_) / gt_pixels_ : 0;
  s.missing_penalty = max_multiple_ * sigma_;
  if (gt_pixels_ > 0) {
    s.mae_all = (sum_abs_ + static_cast<double>(gt_pixels_ - covered_) * s.missing_penalty) /
                static_cast<double>(gt_pixels_);
  }
  int64_t running = 0;
  for (int m = 0; m < max_multiple_; ++m) {
    running += within_[m];
    s.cumulative.push_back(gt_pixels_ > 0 ? static_cast<double>(running) / gt_pixels_ : 0);
  }
  return s;
}

DepthErrorStats CompareDepthMaps(const cv::Mat& depth, const cv::Mat& gt, double sigma,
                                 int max_multiple) {
  DepthErrorAccumulator accumulator(sigma, max_multiple);
  accumulator.Add(depth, gt);
  return accumulator.Finish();
}

namespace {

gl::DepthRenderOptions DepthOnly() {
  gl::DepthRenderOptions o;
  o.world_positions = false;
  o.face_ids = false;
  return o;
}

cv::Mat RenderMeasure(gl::MeshRenderer& renderer, const View& view, DepthMeasure measure) {
  cv::Mat depth = renderer.Render(view, DepthOnly()).depth;
  return measure == DepthMeasure::kRange ? RangeFromDepth(depth, view.intrinsics) : depth;
}

}  // namespace

Evaluation EvaluateMeshes(const gl::GlContext& context, const std::vector<LabeledMesh>& meshes,
                          const Mesh& ground_truth, const Scene& scene,
                          const EvaluateOptions& options) {
  options.Check();
  Evaluation e;
  e.measure = options.measure;
  if (options.all_views) {
    for (size_t i = 0; i < scene.views.size(); ++i) e.views.push_back(static_cast<int>(i));
  } else {
    e.views = options.views.empty() ? std::vector<int>{0} : options.views;
  }
  if (e.views.empty()) throw InputError(scene.source + ": the scene has no views to evaluate");
  for (int v : e.views) {
    if (v >= static_cast<int>(scene.views.size())) {
      throw InputError(fmt::format("{}: view {} does not exist (the scene has {} views)",
                                   scene.source, v, scene.views.size()));
    }
  }
  gl::MeshRenderer gt_renderer(context, ground_truth);
  std::vector<std::unique_ptr<gl::MeshRenderer>> renderers;
  for (const LabeledMesh& m : meshes) {
    if (m.mesh == nullptr) throw InternalError("EvaluateMeshes: null mesh");
    renderers.push_back(std::make_unique<gl::MeshRenderer>(context, *m.mesh));
  }

  // Pass 1 (only without a given Sigma): the median ground-truth depth, from a deterministic
  // subsample of at most ~4M pixels so that thousands of views fit in memory.
  std::vector<cv::Mat> kept_gt;  // reused by pass 2 when there are few views
  const bool keep = e.views.size() <= 8;
  if (options.sigma > 0) {
    e.sigma = options.sigma;
    e.sigma_rule = "given";
  }
  {
    int64_t total = 0;
    for (int v : e.views) {
      total += int64_t{scene.views[v].intrinsics.width} * scene.views[v].intrinsics.height;
    }
    const int64_t stride = std::max<int64_t>(1, total / 4000000);
    std::vector<float> samples;
    int64_t index = 0;
    if (keep || options.sigma == 0) {
      Progress progress("rendering ground-truth depth", static_cast<int64_t>(e.views.size()));
      for (size_t i = 0; i < e.views.size(); ++i) {
        cv::Mat gt = RenderMeasure(gt_renderer, scene.views[e.views[i]], options.measure);
        for (int r = 0; r < gt.rows; ++r) {
          const float* row = gt.ptr<float>(r);
          for (int c = 0; c < gt.cols; ++c, ++index) {
            if (row[c] > 0 && index % stride == 0) samples.push_back(row[c]);
          }
        }
        if (keep) kept_gt.push_back(std::move(gt));
        progress.Update(static_cast<int64_t>(i + 1));
      }
      progress.Finish(static_cast<int64_t>(e.views.size()));
      if (samples.empty()) {
        throw InputError(
            "the ground-truth mesh covers no pixel of the evaluated view(s): wrong "
            "scene, or the mesh is not in the scene's coordinates");
      }
      std::nth_element(samples.begin(), samples.begin() + samples.size() / 2, samples.end());
      e.median_gt_depth = samples[samples.size() / 2];
    }
  }
  if (options.sigma == 0) {
    e.sigma = e.median_gt_depth / kSigmaDepthRatio;
    e.sigma_rule = fmt::format("median ground-truth depth / {:g} = {:.4g} / {:g}", kSigmaDepthRatio,
                               e.median_gt_depth, kSigmaDepthRatio);
  }

  // Pass 2: every mesh against the ground truth, view by view.
  std::vector<DepthErrorAccumulator> totals(meshes.size(),
                                            DepthErrorAccumulator(e.sigma, options.max_multiple));
  e.meshes.resize(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m) e.meshes[m].label = meshes[m].label;
  Progress progress("evaluating views", static_cast<int64_t>(e.views.size()));
  int64_t gt_pixels = 0;
  for (size_t i = 0; i < e.views.size(); ++i) {
    const View& view = scene.views[e.views[i]];
    const cv::Mat gt = keep ? kept_gt[i] : RenderMeasure(gt_renderer, view, options.measure);
    gt_pixels += cv::countNonZero(gt > 0);
    if (i == 0) e.first_gt_depth = gt;
    for (size_t m = 0; m < meshes.size(); ++m) {
      const cv::Mat depth = RenderMeasure(*renderers[m], view, options.measure);
      totals[m].Add(depth, gt);
      e.meshes[m].views.push_back(
          {e.views[i], view.name, CompareDepthMaps(depth, gt, e.sigma, options.max_multiple)});
      if (i == 0) e.meshes[m].first_depth = depth;
    }
    progress.Update(static_cast<int64_t>(i + 1));
  }
  progress.Finish(static_cast<int64_t>(e.views.size()));
  if (gt_pixels == 0) {
    throw InputError(
        "the ground-truth mesh covers no pixel of the evaluated view(s): wrong "
        "scene, or the mesh is not in the scene's coordinates");
  }
  for (size_t m = 0; m < meshes.size(); ++m) e.meshes[m].total = totals[m].Finish();
  return e;
}

std::string FormatEvaluationTable(const Evaluation& e) {
  std::string views;
  for (size_t i = 0; i < e.views.size() && i < 8; ++i) {
    views += (i ? "," : "") + std::to_string(e.views[i]);
  }
  if (e.views.size() > 8) views += fmt::format(",... ({} views)", e.views.size());
  std::string out;
  const int64_t gt_pixels = e.meshes.empty() ? 0 : e.meshes.front().total.gt_pixels;
  out +=
      fmt::format("depth ({}) errors from view {}: {} ground-truth pixels, Sigma = {:.4g} ({})\n",
                  e.measure == DepthMeasure::kRange ? "distance from the camera" : "camera z",
                  views, gt_pixels, e.sigma, e.sigma_rule);
  size_t label_width = 12;
  for (const MeshEvaluation& m : e.meshes) label_width = std::max(label_width, m.label.size());
  const int multiples =
      e.meshes.empty() ? 0 : static_cast<int>(e.meshes[0].total.cumulative.size());
  std::string header = fmt::format("{:<{}}  {:>9} {:>9} {:>9} {:>8} {:>9}", "mesh", label_width,
                                   "MAE", "MRE", "RMS", "coverage", "MAE(all)");
  for (int m = 1; m <= multiples; ++m) header += fmt::format(" {:>5}", fmt::format("<{}S", m));
  out += header + "\n";
  auto row = [&](const std::string& label, const DepthErrorStats& s) {
    std::string line = fmt::format("{:<{}}  {:>9.4f} {:>9.4f} {:>9.4f} {:>7.1f}% {:>9.4f}", label,
                                   label_width, s.mae, s.mre, s.rms, 100 * s.coverage, s.mae_all);
    for (double c : s.cumulative) line += fmt::format(" {:>4.0f}%", 100 * c);
    return line + "\n";
  };
  for (const MeshEvaluation& m : e.meshes) {
    out += row(m.label, m.total);
    if (m.views.size() > 1 && m.views.size() <= 50) {
      for (const ViewEvaluation& v : m.views) {
        out += row(fmt::format("  view {} {}", v.view, v.view_name), v.stats);
      }
    }
  }
  out += fmt::format(
      "(MAE, MRE = mean |d-d*|/d* and RMS over the pixels the mesh covers; MAE(all) "
      "over all ground-truth pixels, a missed pixel counting {}*Sigma; <mS = share of "
      "ground-truth pixels with error below m*Sigma; scene units)\n",
      multiples);
  return out;
}

nlohmann::json EvaluationToJson(const Evaluation& e) {
  auto stats = [](const DepthErrorStats& s) {
    return nlohmann::json{{"gt_pixels", s.gt_pixels},
                          {"covered_pixels", s.covered_pixels},
                          {"mae", s.mae},
                          {"mre", s.mre},
                          {"rms", s.rms},
                          {"coverage", s.coverage},
                          {"mae_all", s.mae_all},
                          {"missing_penalty", s.missing_penalty},
                          {"cumulative", s.cumulative}};
  };
  nlohmann::json meshes = nlohmann::json::array();
  for (const MeshEvaluation& m : e.meshes) {
    nlohmann::json views = nlohmann::json::array();
    for (const ViewEvaluation& v : m.views) {
      nlohmann::json entry = stats(v.stats);
      entry["view"] = v.view;
      entry["name"] = v.view_name;
      views.push_back(entry);
    }
    meshes.push_back({{"label", m.label}, {"total", stats(m.total)}, {"views", views}});
  }
  return {{"views", e.views},
          {"sigma", e.sigma},
          {"sigma_rule", e.sigma_rule},
          {"depth", DepthMeasureName(e.measure)},
          {"median_gt_depth", e.median_gt_depth},
          {"meshes", meshes}};
}

void WriteEvaluationFiles(const Evaluation& e, const EvaluationFiles& files) {
  if (!(files.error_max >= 0)) throw InputError("--error-max: must be >= 0");
  if (!files.json.empty()) {
    nlohmann::json json = EvaluationToJson(e);
    if (!files.ground_truth_name.empty()) json["ground_truth"] = files.ground_truth_name;
    if (!files.scene_name.empty()) json["scene"] = files.scene_name;
    WriteFileAtomically(
        files.json, [&](std::ostream& out) { out << json.dump(2) << "\n"; },
        /*binary=*/false);
  }
  if (!files.error_image.empty()) {
    std::vector<ErrorPanel> panels;
    for (const MeshEvaluation& m : e.meshes) panels.push_back({m.label, m.first_depth});
    const double max_error = files.error_max > 0 ? files.error_max : 5 * e.sigma;
    WritePng(files.error_image, ErrorFigure(panels, e.first_gt_depth, max_error));
  }
  if (!files.plot.empty()) {
    std::vector<PlotCurve> curves;
    for (const MeshEvaluation& m : e.meshes) curves.push_back({m.label, m.total.cumulative});
    const std::string title =
        e.views.size() == 1 ? fmt::format("Cumulative depth error from view {}", e.views[0])
                            : fmt::format("Cumulative depth error over {} views", e.views.size());
    WritePng(files.plot, CumulativePlot(curves, e.sigma, title));
  }
}

}  // namespace ms
