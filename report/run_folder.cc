#include "report/run_folder.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "base/error.h"
#include "base/file_util.h"
#include "refine/refine_checkpoint.h"
#include "scene/h5_file.h"
#include "scene/scene_h5.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

nlohmann::json ReadJsonFile(const fs::path& path) {
  try {
    return nlohmann::json::parse(ReadFileToString(path));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: not valid JSON ({})", path.string(), e.what()));
  }
}

// summary.json's fields the report relies on, each checked for its type.
void CheckSummary(const nlohmann::json& summary, const fs::path& path) {
  const auto require = [&](const char* field, bool ok) {
    if (!ok)
      throw InputError(
          fmt::format("{}: field '{}' missing or of the wrong type", path.string(), field));
  };
  require("status", summary.contains("status") && summary["status"].is_string());
  require("input", summary.contains("input") && summary["input"].is_string());
  require("iterations", summary.contains("iterations") && summary["iterations"].is_array());
  for (const nlohmann::json& row : summary["iterations"]) {
    require("iterations[]",
            row.is_object() && row.contains("iteration") && row["iteration"].is_number_integer());
  }
}

// The run's input: the absolute path recorded, else the path as given (from the current
// directory, then from the run folder's parent).
fs::path FindInput(const nlohmann::json& summary, const fs::path& dir) {
  for (const char* field : {"input_absolute", "input"}) {
    if (!summary.contains(field) || !summary[field].is_string()) continue;
    const fs::path path = summary[field].get<std::string>();
    if (path.empty()) continue;
    if (fs::exists(path)) return path;
    if (path.is_relative() && fs::exists(dir.parent_path() / path)) return dir.parent_path() / path;
  }
  return {};
}

// A `synth` dataset keeps synth.json at its root; the input is scene.h5 or sparse/ inside it,
// or the root itself.
std::optional<GroundTruthFile> FindSynthGroundTruth(const fs::path& input) {
  if (input.empty()) return std::nullopt;
  fs::path folder = fs::is_directory(input) ? input : input.parent_path();
  for (int up = 0; up < 2 && !folder.empty(); ++up, folder = folder.parent_path()) {
    const fs::path synth = folder / "synth.json";
    if (!fs::exists(synth)) continue;
    const nlohmann::json j = ReadJsonFile(synth);
    GroundTruthFile gt;
    gt.path = (folder /
               j.value(nlohmann::json::json_pointer("/files/ground_truth"), std::string("gt.ply")))
                  .string();
    gt.view = j.value("evaluation_view", 0);
    gt.source = "the synth dataset's " + synth.string();
    if (!fs::exists(gt.path)) return std::nullopt;
    return gt;
  }
  return std::nullopt;
}

}  // namespace

RunFolder ReadRunFolder(const std::string& dir_name, const std::string& ground_truth) {
  const fs::path dir(dir_name);
  RequireDirectory(dir, "run folder");
  RunFolder run;
  run.dir = dir_name;
  const fs::path summary_path = dir / "summary.json";
  RequireFile(summary_path, "summary.json of the run");
  run.summary = ReadJsonFile(summary_path);
  CheckSummary(run.summary, summary_path);
  const fs::path h5 = dir / "run.h5";
  RequireFile(h5, "run.h5 of the run");
  run.scene = ReadSceneH5(H5File::OpenReadOnly(h5.string()), "/scene");
  for (const auto& [label, file] :
       {std::pair{"initial", "initial.ply"}, {"swept", "final.ply"}, {"refined", "refined.ply"}}) {
    if (fs::exists(dir / file)) run.meshes.push_back({label, (dir / file).string()});
  }
  const std::string done = RefineDonePath((dir / "refined.ply").string());
  if (fs::exists(done) && fs::exists(dir / "refined.ply")) run.refined = ReadJsonFile(done);
  if (!ground_truth.empty()) {
    RequireFile(ground_truth, "--report.ground-truth mesh");
    run.ground_truth = GroundTruthFile{ground_truth, 0, "--report.ground-truth"};
  } else {
    run.ground_truth = FindSynthGroundTruth(FindInput(run.summary, dir));
  }
  if (run.ground_truth && (run.ground_truth->view < 0 ||
                           run.ground_truth->view >= static_cast<int>(run.scene.views.size()))) {
    run.ground_truth->view = 0;
  }
  return run;
}

std::vector<int> SpreadViews(int num_views, int count, int first) {
  std::vector<int> views;
  if (num_views <= 0 || count <= 0) return views;
  count = std::min(count, num_views);
  for (int i = 0; i < count; ++i) {
    const int view = (first + static_cast<int>(int64_t{i} * num_views / count)) % num_views;
    views.push_back(view);
  }
  return views;
}

}  // namespace ms
