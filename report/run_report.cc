#include "report/run_report.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "base/error.h"
#include "base/file_util.h"
#include "coordinator/coordinator.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "refine/refine_options.h"
#include "report/html_page.h"
#include "report/svg_chart.h"
#include "tools/consistency.h"
#include "tools/evaluate.h"
#include "tools/plot.h"
#include "tools/render.h"

namespace ms {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct LoadedMesh {
  RunMeshFile file;
  Mesh mesh;
};

std::string Percent(int64_t part, int64_t whole) {
  return whole > 0 ? fmt::format("{:.1f}%", 100.0 * static_cast<double>(part) / whole) : "–";
}

std::string Section(const std::string& id, const std::string& title, const std::string& body) {
  return fmt::format("<section id=\"{}\">\n<h2>{}</h2>\n{}</section>\n", id, EscapeHtml(title),
                     body);
}

std::string Note(const std::string& text) {
  return "<p class=\"note\">" + EscapeHtml(text) + "</p>\n";
}

// A number of summary.json's iteration rows as a chart series (NaN where absent).
ChartSeries Column(const json& rows, const char* field, const std::string& name,
                   bool skip_build = false) {
  ChartSeries series{name, {}};
  for (const json& row : rows) {
    const bool build = row.value("iteration", 0) == 0;
    series.values.push_back(row.contains(field) && row[field].is_number() && !(skip_build && build)
                                ? row[field].get<double>()
                                : std::numeric_limits<double>::quiet_NaN());
  }
  return series;
}

// ---- Sections

std::string HeaderSection(const RunFolder& run, const std::vector<LoadedMesh>& meshes) {
  const json& s = run.summary;
  std::string body = "<table class=\"facts\">\n";
  const auto fact = [&](const std::string& name, const std::string& value) {
    body += "<tr><th>" + EscapeHtml(name) + "</th><td>" + EscapeHtml(value) + "</td></tr>\n";
  };
  fact("input", s.value("input", ""));
  fact("scene", fmt::format("{} views, {} points", run.scene.views.size(),
                            s.value(json::json_pointer("/scene/points"), int64_t{0})));
  fact("status", s.value("status", "") + " (" + s.value("stop_reason", "") + ")");
  fact("iterations", std::to_string(s.value("iterations_completed", 0)));
  fact("workers", std::to_string(s.contains("workers") ? s["workers"].size() : 0));
  fact("coordinator time",
       fmt::format("{:.1f} s (this process{})", s.value("seconds_this_process", 0.0),
                   s.value("resumed", false) ? ", resumed" : ""));
  fact("coordinator peak memory",
       fmt::format("{:.0f} MiB", s.value("peak_rss_bytes_this_process", 0.0) / (1 << 20)));
  if (run.refined) {
    fact("refinement (the process that finished it)",
         fmt::format("{} iterations, {:.1f} s, final energy {:.4f}",
                     run.refined->value("iterations", json::array()).size(),
                     run.refined->value("seconds", 0.0), run.refined->value("final_energy", 0.0)));
  }
  std::string files;
  for (const LoadedMesh& m : meshes) {
    files += (files.empty() ? "" : ", ") + fs::path(m.file.path).filename().string();
  }
  fact("meshes", files.empty() ? "none written yet" : files);
  body += "</table>\n";
  return Section("run", "Run", body);
}

std::string OptionRows(const json& recorded, const OptionValues& defaults, bool only_changed) {
  std::map<std::string, std::string> default_of(defaults.begin(), defaults.end());
  HtmlTable table({"option", "value", "default"}, "options");
  int rows = 0;
  for (const auto& [key, value] : recorded.items()) {
    const std::string text = value.is_string() ? value.get<std::string>() : value.dump();
    const auto d = default_of.find(key);
    const std::string def = d == default_of.end() ? "" : d->second;
    if (only_changed && def == text) continue;
    table.AddRow({"--" + key, text, def});
    ++rows;
  }
  return rows > 0 ? table.Html() : Note("every option at its default");
}

std::string OptionsSection(const RunFolder& run) {
  std::string body;
  const json none = json::object();
  const json& sweep = run.summary.contains("options") ? run.summary["options"] : none;
  const OptionValues sweep_defaults = CoordinatorOptionValues(CoordinatorOptions{});
  if (sweep.empty()) {
    body += Note("summary.json records no options (a run of an older manisweep)");
  } else {
    body += "<h3>Reconstruction: options not at their defaults</h3>\n" +
            OptionRows(sweep, sweep_defaults, true) +
            "<details><summary>every option of the reconstruction</summary>\n" +
            OptionRows(sweep, sweep_defaults, false) + "</details>\n";
  }
  if (run.refined && run.refined->contains("options")) {
    const OptionValues refine_defaults = OptionGroupValues(RefineOptions{});
    body += "<h3>Refinement: options not at their defaults</h3>\n" +
            OptionRows((*run.refined)["options"], refine_defaults, true) +
            "<details><summary>every option of the refinement</summary>\n" +
            OptionRows((*run.refined)["options"], refine_defaults, false) + "</details>\n";
  }
  return Section("options", "Options", body);
}

std::string IterationCharts(const RunFolder& run) {
  const json& rows = run.summary["iterations"];
  LineChart points{"Points per iteration", "iteration", "points", {}, {}};
  for (const json& row : rows) points.xs.push_back(row.value("iteration", 0));
  LineChart mesh = points, seconds = points;
  mesh.title = "Mesh size after each iteration";
  mesh.y_label = "vertices";
  seconds.title = "Coordinator seconds per iteration";
  seconds.y_label = "seconds";
  points.series = {Column(rows, "points_found", "found", true),
                   Column(rows, "points_inserted", "inserted", true),
                   Column(rows, "discarded_conflict", "conflicts", true),
                   Column(rows, "discarded_duplicate", "duplicates", true),
                   Column(rows, "discarded_outside", "outside", true)};
  mesh.series = {Column(rows, "vertices", "vertices")};
  seconds.series = {
      Column(rows, "seconds_total", "total"), Column(rows, "seconds_sweep", "sweep", true),
      Column(rows, "seconds_insert", "insert"), Column(rows, "seconds_extract", "extract"),
      Column(rows, "seconds_checkpoint", "checkpoint")};
  std::string body = "<div class=\"charts\">\n" + SvgLineChart(points) + SvgLineChart(mesh) +
                     SvgLineChart(seconds);
  if (run.refined && (*run.refined).contains("iterations")) {
    LineChart energy{"Refinement energy", "iteration", "mean 1 - ZNCC", {}, {}};
    ChartSeries e{"energy", {}};
    for (const json& it : (*run.refined)["iterations"]) {
      energy.xs.push_back(it.value("iteration", 0));
      e.values.push_back(it.value("energy", 0.0));
    }
    energy.series = {e};
    body += SvgLineChart(energy);
  }
  body += "</div>\n";
  HtmlTable table({"iteration", "found", "inserted", "conflicts", "duplicates", "outside",
                   "vertices", "faces", "cameras in matter", "seconds"},
                  "numbers");
  for (const json& row : rows) {
    const auto n = [&](const char* f) { return std::to_string(row.value(f, int64_t{0})); };
    table.AddRow({n("iteration"), n("points_found"), n("points_inserted"), n("discarded_conflict"),
                  n("discarded_duplicate"), n("discarded_outside"), n("vertices"), n("faces"),
                  n("cameras_in_matter"), fmt::format("{:.2f}", row.value("seconds_total", 0.0))});
  }
  body += "<details><summary>the figures of every iteration</summary>\n" + table.Html() +
          "</details>\n";
  return Section("iterations", "Iterations", body);
}

cv::Mat Labelled(cv::Mat picture, const std::string& label) {
  cv::putText(picture, label, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, {255, 255, 255}, 3,
              cv::LINE_AA);
  cv::putText(picture, label, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, {30, 30, 30}, 1,
              cv::LINE_AA);
  return picture;
}

// The photograph of `view` at the pictures' size, or nothing when it cannot be read.
std::optional<cv::Mat> Photograph(const View& view, int max_size) {
  if (view.image_path.empty()) return std::nullopt;
  cv::Mat image = cv::imread(view.image_path, cv::IMREAD_COLOR);
  if (image.empty()) return std::nullopt;
  const View scaled = ScaledView(view, max_size);
  cv::resize(image, image, {scaled.intrinsics.width, scaled.intrinsics.height}, 0, 0,
             cv::INTER_AREA);
  return image;
}

std::string PicturesSection(const gl::GlContext& gl, const RunFolder& run,
                            const std::vector<LoadedMesh>& meshes, const ReportOptions& options) {
  const int first = run.ground_truth ? run.ground_truth->view : 0;
  const std::vector<int> views =
      SpreadViews(static_cast<int>(run.scene.views.size()), options.cameras, first);
  if (views.empty() || meshes.empty()) return "";
  ShadedRenderOptions render;
  render.max_size = options.picture_size;
  std::string body = Note(
      "Each mesh shaded as seen from the camera; faces seen from behind are red. The "
      "photograph comes first where it can be read.");
  for (const int v : views) {
    const View& view = run.scene.views[v];
    body +=
        fmt::format("<h3>view {} ({})</h3>\n<div class=\"pictures\">\n", v, EscapeHtml(view.name));
    if (const std::optional<cv::Mat> photo = Photograph(view, options.picture_size)) {
      body += PngImageTag(Labelled(*photo, "photograph"), "view " + std::to_string(v) + " photo");
    }
    for (const LoadedMesh& m : meshes) {
      body += PngImageTag(Labelled(RenderShaded(gl, m.mesh, view, render), m.file.label),
                          m.file.label + " mesh from view " + std::to_string(v));
    }
    body += "</div>\n";
  }
  return Section("pictures", "Pictures", body);
}

std::string MeshCheckCell(const MeshReport& r) {
  if (r.is_valid) return "valid: closed 2-manifold, no self-intersection, float-robust";
  std::string problems;
  for (const std::string& p : r.Problems()) problems += (problems.empty() ? "" : "; ") + p;
  return "NOT VALID: " + problems;
}

std::string MeshesSection(const RunFolder& run, const std::vector<LoadedMesh>& meshes,
                          const ReportOptions& options, std::string* per_camera) {
  HtmlTable table({"mesh", "vertices", "faces", "components", "genus", "check-mesh",
                   "photo-consistent (all pixels)", "covered", "consistent of covered"},
                  "numbers");
  std::string consistency_note;
  ConsistencyOptions consistency;
  HtmlTable cameras({"camera", "mesh", "consistent", "covered", "pixels"}, "numbers");
  for (const LoadedMesh& m : meshes) {
    const MeshReport check = CheckMesh(m.mesh);
    std::vector<std::string> row = {
        m.file.label + " (" + fs::path(m.file.path).filename().string() + ")",
        std::to_string(check.num_vertices),
        std::to_string(check.num_faces),
        std::to_string(check.num_components),
        check.genus ? std::to_string(*check.genus) : "–",
        MeshCheckCell(check)};
    if (options.consistency && consistency_note.empty()) {
      try {
        const ConsistencyReport c = MeasureConsistency(run.scene, m.mesh, consistency);
        row.push_back(Percent(c.total.consistent, c.total.pixels));
        row.push_back(Percent(c.total.covered, c.total.pixels));
        row.push_back(Percent(c.total.consistent, c.total.covered));
        for (const CameraConsistency& cam : c.cameras) {
          cameras.AddRow({std::to_string(cam.camera), m.file.label,
                          Percent(cam.consistent, cam.pixels), Percent(cam.covered, cam.pixels),
                          std::to_string(cam.pixels)});
        }
      } catch (const InputError& e) {
        consistency_note = std::string("photo-consistency not measured: ") + e.what();
      }
    }
    row.resize(9, "–");
    table.AddRow(row);
  }
  std::string body = table.Html();
  if (!options.consistency) {
    body += Note("photo-consistency not measured (--report.consistency=false)");
  } else if (!consistency_note.empty()) {
    body += Note(consistency_note);
  } else {
    body += Note(fmt::format(
        "Photo-consistency as `manisweep consistency` measures it: the share of all image "
        "pixels whose NCC against a neighbour, reprojected through the mesh, is above {:.2f}.",
        consistency.ncc_threshold));
    *per_camera = "<details><summary>photo-consistency per camera</summary>\n" + cameras.Html() +
                  "</details>\n";
  }
  return body;
}

std::string AccuracySection(const gl::GlContext& gl, const RunFolder& run,
                            const std::vector<LoadedMesh>& meshes, const ReportOptions& options) {
  if (!run.ground_truth || meshes.empty()) return "";
  const Mesh truth = ReadMesh(run.ground_truth->path);
  EvaluateOptions evaluate;
  evaluate.views = {run.ground_truth->view};
  evaluate.sigma = options.sigma;
  std::vector<LabeledMesh> labelled;
  for (const LoadedMesh& m : meshes) labelled.push_back({m.file.label, &m.mesh});
  const Evaluation e = EvaluateMeshes(gl, labelled, truth, run.scene, evaluate);
  HtmlTable table(
      {"mesh", "MAE (every pixel)", "MAE (covered)", "RMS", "coverage", "within Σ", "within 3Σ"},
      "numbers");
  for (const MeshEvaluation& m : e.meshes) {
    const DepthErrorStats& t = m.total;
    const auto within = [&](size_t k) {
      return t.cumulative.size() > k ? fmt::format("{:.1f}%", 100 * t.cumulative[k]) : "–";
    };
    table.AddRow({m.label, fmt::format("{:.4f}", t.mae_all), fmt::format("{:.4f}", t.mae),
                  fmt::format("{:.4f}", t.rms), fmt::format("{:.1f}%", 100 * t.coverage), within(0),
                  within(2)});
  }
  const std::string text = fmt::format(
      "Depth error against the ground truth {} ({}) from view {}, depth as camera z, Σ = {:.4g} "
      "({}). A pixel the mesh misses counts as an error of {} Σ in the first column.",
      fs::path(run.ground_truth->path).filename().string(), run.ground_truth->source,
      run.ground_truth->view, e.sigma, e.sigma_rule, evaluate.max_multiple);
  if (options.cameras == 0) {  // no pictures
    return Section("accuracy", "Accuracy against the ground truth", Note(text) + table.Html());
  }
  // The paper's Figure 5 (first row): each mesh's depth error from the evaluation view.
  std::vector<ErrorPanel> panels;
  for (const MeshEvaluation& m : e.meshes) panels.push_back({m.label, m.first_depth});
  const double max_error = 5 * e.sigma;
  const std::string figure =
      PngImageTag(ErrorFigure(panels, e.first_gt_depth, max_error, options.picture_size),
                  "depth error of each mesh from view " + std::to_string(run.ground_truth->view));
  const std::string caption = Note(fmt::format(
      "|d - d*| from view {}, blue 0 to red {:.4g} (5 Σ) and above; black: no ground truth, "
      "white: the mesh misses a pixel the ground truth has.",
      run.ground_truth->view, max_error));
  return Section(
      "accuracy", "Accuracy against the ground truth",
      Note(text) + table.Html() + "<div class=\"pictures\">" + figure + "</div>\n" + caption);
}

constexpr const char* kStyle = R"(
body { font-family: sans-serif; margin: 24px auto; max-width: 1600px; color: #222; }
h1 { font-size: 22px; } h2 { font-size: 18px; border-bottom: 1px solid #ccc; }
h3 { font-size: 15px; } .note { color: #555; font-size: 13px; max-width: 900px; }
table { border-collapse: collapse; font-size: 13px; margin: 8px 0; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: left; }
table.numbers td { text-align: right; } table.numbers td:first-child { text-align: left; }
.charts svg { margin: 4px; border: 1px solid #eee; }
.pictures img { margin: 2px; border: 1px solid #ddd; max-width: 100%; height: auto; }
)";

// Records on <html> what the page itself can tell once loaded: images that did not decode and
// script errors (tests/tools/report_browser_test.py reads it with a headless browser).
constexpr const char* kErrorTrap =
    "<script>window.__reportErrors=0;window.addEventListener('error',function(){"
    "window.__reportErrors++;},true);</script>\n";
constexpr const char* kSelfCheck =
    "<script>window.addEventListener('load',function(){var bad=0,imgs=document.images;"
    "for(var i=0;i<imgs.length;i++){if(!imgs[i].complete||imgs[i].naturalWidth===0)bad++;}"
    "var t=performance.getEntriesByType('navigation')[0];"
    "document.documentElement.setAttribute('data-report-check','images='+imgs.length+"
    "' undecoded='+bad+' errors='+window.__reportErrors+' load_ms='+"
    "Math.round(t?t.loadEventStart:0));});</script>\n";

}  // namespace

std::string BuildRunReport(const gl::GlContext& gl, const RunFolder& run,
                           const ReportOptions& options) {
  options.Check();
  std::vector<LoadedMesh> meshes;
  for (const RunMeshFile& file : run.meshes) meshes.push_back({file, ReadMesh(file.path)});
  std::string per_camera;
  const std::string mesh_table = MeshesSection(run, meshes, options, &per_camera);
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += kErrorTrap;
  html += "<title>manisweep run report: " + EscapeHtml(run.dir) + "</title>\n<style>" +
          std::string(kStyle) + "</style>\n</head>\n<body>\n";
  html += "<h1>manisweep run report: " + EscapeHtml(run.dir) + "</h1>\n";
  html += HeaderSection(run, meshes);
  html += Section("meshes", "Meshes", mesh_table);
  html += AccuracySection(gl, run, meshes, options);
  html += PicturesSection(gl, run, meshes, options);
  html += IterationCharts(run);
  if (!per_camera.empty()) html += Section("cameras", "Cameras", per_camera);
  html += OptionsSection(run);
  html += Note("Written by `manisweep report " + run.dir +
               "` from summary.json, run.h5 and the meshes of the folder (docs/guides/report.md).");
  html += kSelfCheck;
  html += "</body>\n</html>\n";
  return html;
}

std::string WriteRunReport(const std::string& run_dir, const ReportOptions& options,
                           const std::string& output) {
  options.Check();
  const RunFolder run = ReadRunFolder(run_dir, options.ground_truth);
  const gl::GlContext gl;
  const std::string html = BuildRunReport(gl, run, options);
  const std::string path = output.empty() ? (fs::path(run_dir) / "report.html").string() : output;
  WriteFileAtomically(
      path, [&](std::ostream& out) { out << html; }, false);
  spdlog::info("wrote the run report {} ({:.1f} MB)", path, html.size() / 1e6);
  return path;
}

void WriteRunReportAfterRun(const std::string& run_dir, const RunReportRequest& request) {
  if (!request.write) return;
  try {
    WriteRunReport(run_dir, request.options);
  } catch (const std::exception& e) {
    spdlog::warn("the run report was not written: {}", e.what());
  }
}

}  // namespace ms
