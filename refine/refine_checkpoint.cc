#include "refine/refine_checkpoint.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "mesh/mesh_io.h"
#include "proto/content_hash.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

std::string MeshPath(const std::string& output) { return output + ".checkpoint.ply"; }
std::string AcceptedPath(const std::string& output) { return output + ".checkpoint.accepted.ply"; }
std::string JsonPath(const std::string& output) { return output + ".checkpoint.json"; }
std::string DonePath(const std::string& output) { return output + ".done.json"; }

}  // namespace

void WriteRefineCheckpoint(const std::string& output, const Mesh& mesh, const RefineState& state,
                           const std::string& fingerprint) {
  WriteMesh(mesh, MeshPath(output));
  if (!state.accepted.empty()) {
    Mesh accepted;
    accepted.vertices = state.accepted;
    accepted.faces = mesh.faces;
    WriteMesh(accepted, AcceptedPath(output));
  }
  nlohmann::json j = {{"format", "manisweep refine checkpoint"},
                      {"version", 1},
                      {"fingerprint", fingerprint},
                      {"level_index", state.level_index},
                      {"iteration_in_level", state.iteration_in_level},
                      {"iterations_done", state.iterations_done},
                      {"scale", state.scale},
                      {"accepted_energy", state.accepted_energy},
                      {"has_accepted", !state.accepted.empty()},
                      {"tolerance", state.tolerance},
                      {"camera_clearance", state.camera_clearance}};
  if (!state.stuck.empty()) j["stuck"] = state.stuck;  // only with --refine.unfold
  WriteFileAtomically(
      JsonPath(output), [&](std::ostream& os) { os << j.dump(2) << "\n"; }, false);
}

std::optional<RefineCheckpoint> ReadRefineCheckpoint(const std::string& output,
                                                     const std::string& fingerprint) {
  const std::string json_path = JsonPath(output);
  if (!fs::exists(json_path)) return std::nullopt;
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadFileToString(json_path));
    if (j.at("format") != "manisweep refine checkpoint" || j.at("version") != 1) {
      throw InputError(json_path + ": not a manisweep refine checkpoint of version 1");
    }
    if (j.at("fingerprint") != fingerprint) {
      throw InputError(json_path + ": made for another refinement (" +
                       j.at("fingerprint").get<std::string>() + "); this one is (" + fingerprint +
                       "): remove it or run without --resume");
    }
    RefineCheckpoint c;
    c.state.level_index = j.at("level_index").get<int>();
    c.state.iteration_in_level = j.at("iteration_in_level").get<int>();
    c.state.iterations_done = j.at("iterations_done").get<int>();
    c.state.scale = j.at("scale").get<double>();
    c.state.accepted_energy = j.at("accepted_energy").get<double>();
    c.state.tolerance = j.at("tolerance").get<double>();
    c.state.camera_clearance = j.value("camera_clearance", 0.0);
    c.state.stuck = j.value("stuck", std::vector<int32_t>());
    c.mesh = ReadMesh(MeshPath(output));
    for (int32_t v : c.state.stuck) {
      if (v < 0 || static_cast<size_t>(v) >= c.mesh.vertices.size()) {
        throw InputError(json_path + ": stuck vertex " + std::to_string(v) + " out of range (" +
                         std::to_string(c.mesh.vertices.size()) + " vertices)");
      }
    }
    if (j.at("has_accepted").get<bool>()) {
      Mesh accepted = ReadMesh(AcceptedPath(output));
      if (accepted.vertices.size() != c.mesh.vertices.size()) {
        throw InputError(AcceptedPath(output) + ": " + std::to_string(accepted.vertices.size()) +
                         " vertices, the checkpoint's mesh has " +
                         std::to_string(c.mesh.vertices.size()));
      }
      c.state.accepted = std::move(accepted.vertices);
    }
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(json_path + ": " + e.what());
  }
}

void RemoveRefineCheckpoint(const std::string& output) {
  for (const std::string& path : {JsonPath(output), MeshPath(output), AcceptedPath(output)}) {
    std::error_code ignored;
    fs::remove(path, ignored);
  }
}

std::string RefineDonePath(const std::string& output) { return DonePath(output); }

void WriteRefineDone(const std::string& output, const std::string& fingerprint,
                     const RefineStats& stats, const OptionValues& options) {
  const FileHash hash = HashFile(output);
  nlohmann::json j = {{"format", "manisweep refine done"},  {"version", 1},
                      {"fingerprint", fingerprint},         {"size", hash.size},
                      {"hash", HashHex(hash.hash)},         {"seconds", stats.seconds},
                      {"final_energy", stats.final_energy}, {"splits", stats.splits},
                      {"collapses", stats.collapses},       {"flips", stats.flips}};
  j["options"] = nlohmann::json::object();
  for (const auto& [key, value] : options) j["options"][key] = value;
  j["iterations"] = nlohmann::json::array();
  for (const RefineIteration& it : stats.iterations) {
    j["iterations"].push_back({{"level", it.level},
                               {"iteration", it.iteration},
                               {"energy", it.energy},
                               {"rejected", it.rejected},
                               {"moved", it.moved},
                               {"seconds", it.seconds}});
  }
  WriteFileAtomically(
      DonePath(output), [&](std::ostream& os) { os << j.dump(2) << "\n"; }, false);
}

bool RefineIsDone(const std::string& output, const std::string& fingerprint) {
  if (!fs::exists(DonePath(output)) || !fs::exists(output)) return false;
  try {
    const nlohmann::json j = nlohmann::json::parse(ReadFileToString(DonePath(output)));
    if (j.value("format", "") != "manisweep refine done" ||
        j.value("fingerprint", "") != fingerprint) {
      return false;
    }
    const FileHash hash = HashFile(output);
    return j.value("size", uint64_t{0}) == hash.size && j.value("hash", "") == HashHex(hash.hash);
  } catch (const nlohmann::json::exception&) {
    return false;  // unreadable: refine again
  }
}

}  // namespace ms
