// What a finished (or interrupted) run folder holds, read for the run report: summary.json
// (status, input, options, per-iteration statistics; coordinator/run_store.h), the scene
// recorded in run.h5, the meshes written (initial, swept, refined), the refinement's record
// (refined.ply.done.json) and, for a `synth` dataset, its ground truth.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace ms {

struct RunMeshFile {
  std::string label;  // "initial", "swept", "refined"
  std::string path;
};

struct GroundTruthFile {
  std::string path;
  int view = 0;        // the view the dataset is evaluated from (synth.json), else 0
  std::string source;  // how it was found, for the report's text
};

struct RunFolder {
  std::string dir;
  nlohmann::json summary;                 // summary.json
  std::optional<nlohmann::json> refined;  // refined.ply.done.json, when refinement finished
  Scene scene;                            // run.h5's /scene
  std::vector<RunMeshFile> meshes;        // those present, in pipeline order
  std::optional<GroundTruthFile> ground_truth;
};

// Reads `dir`. `ground_truth` empty: a `synth` dataset's ground truth is looked for beside the
// run's input (synth.json in its folder or the folder above). Throws InputError naming the file
// and field when summary.json or run.h5 is missing or malformed.
RunFolder ReadRunFolder(const std::string& dir, const std::string& ground_truth = "");

// The views to picture: `count` spread evenly over `num_views`, the evaluation view first.
std::vector<int> SpreadViews(int num_views, int count, int first = 0);

}  // namespace ms
