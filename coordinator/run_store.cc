#include "coordinator/run_store.h"

#include <fmt/format.h>

#include <functional>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "base/memory.h"
#include "proto/content_hash.h"
#include "scene/h5_file.h"
#include "scene/scene_h5.h"

namespace ms {
namespace {

constexpr char kRunFormat[] = "manisweep-run";
constexpr int64_t kRunFormatVersion = 1;

// A column of a statistics table and how it maps to the struct: the one list of a table's
// columns writes run.h5, reads it back and writes summary.json's rows.
template <typename Row>
struct Column {
  H5Column column;
  // Added after run.h5's format was fixed: runs written before it have no such column, and
  // the field stays 0 when they are read.
  bool added_later = false;
  std::function<H5Value(const Row&)> get;
  // Reads the column into rows (resized to its length).
  std::function<void(const H5File&, const std::string& table, std::vector<Row>*)> read;
  std::function<void(const Row&, nlohmann::json*)> to_json;
};

enum class Since { kFirstFormat, kAddedLater };

template <typename Row, typename T>
Column<Row> Field(const char* name, T Row::*member, Since since = Since::kFirstFormat) {
  Column<Row> c;
  c.column.name = name;
  c.added_later = since == Since::kAddedLater;
  if constexpr (std::is_same_v<T, double>) c.column.type = H5Type::kFloat64;
  if constexpr (std::is_same_v<T, int32_t>) c.column.type = H5Type::kInt32;
  if constexpr (std::is_same_v<T, int64_t>) c.column.type = H5Type::kInt64;
  if constexpr (std::is_same_v<T, std::string>) {
    c.column.type = H5Type::kString;
    c.column.string_width = 256;
  }
  c.get = [member](const Row& row) { return H5Value(row.*member); };
  c.read = [member, name](const H5File& file, const std::string& table, std::vector<Row>* rows) {
    const std::vector<T> values = file.ReadColumn<T>(table, name);
    rows->resize(values.size());
    for (size_t i = 0; i < values.size(); ++i) (*rows)[i].*member = values[i];
  };
  c.to_json = [member, name](const Row& row, nlohmann::json* out) { (*out)[name] = row.*member; };
  return c;
}

std::vector<Column<IterationStats>> IterationColumns() {
  using S = IterationStats;
  return {Field("iteration", &S::iteration),
          Field("jobs", &S::jobs),
          Field("jobs_bad", &S::jobs_bad),
          Field("jobs_requeued", &S::jobs_requeued),
          Field("cameras_skipped", &S::cameras_skipped),
          Field("workers", &S::workers),
          Field("points_found", &S::points_found),
          Field("points_inserted", &S::points_inserted),
          Field("discarded_conflict", &S::discarded_conflict),
          Field("discarded_duplicate", &S::discarded_duplicate),
          Field("discarded_outside", &S::discarded_outside),
          Field("vertices", &S::vertices),
          Field("faces", &S::faces),
          Field("outside_cells", &S::outside_cells),
          Field("cameras_in_matter", &S::cameras_in_matter, Since::kAddedLater),
          Field("job_bytes", &S::job_bytes, Since::kAddedLater),
          Field("job_max_bytes", &S::job_max_bytes, Since::kAddedLater),
          Field("jobs_smoothed", &S::jobs_smoothed, Since::kAddedLater),
          Field("image_noise_max", &S::image_noise_max, Since::kAddedLater),
          Field("witness_rays", &S::witness_rays, Since::kAddedLater),
          Field("cleanup_collapses", &S::cleanup_collapses),
          Field("cleanup_splits", &S::cleanup_splits),
          Field("float_problems_left", &S::float_problems_left),
          Field("seconds_jobs", &S::seconds_jobs),
          Field("seconds_sweep", &S::seconds_sweep),
          Field("seconds_kernel", &S::seconds_kernel),
          Field("seconds_insert", &S::seconds_insert),
          Field("seconds_insert_early", &S::seconds_insert_early, Since::kAddedLater),
          Field("seconds_extract", &S::seconds_extract),
          Field("seconds_checkpoint", &S::seconds_checkpoint),
          Field("seconds_total", &S::seconds_total)};
}

std::vector<Column<WorkerIterationStats>> WorkerColumns() {
  using W = WorkerIterationStats;
  return {Field("iteration", &W::iteration), Field("worker", &W::worker), Field("jobs", &W::jobs),
          Field("points", &W::points), Field("seconds_kernel", &W::seconds_kernel)};
}

template <typename Row>
void WriteTable(H5File& file, const std::string& table, const std::vector<Column<Row>>& columns,
                const std::vector<Row>& rows) {
  std::vector<H5Column> spec;
  for (const auto& c : columns) spec.push_back(c.column);
  file.CreateTable(table, spec);
  for (const Row& row : rows) {
    std::vector<H5Value> values;
    for (const auto& c : columns) values.push_back(c.get(row));
    file.AppendRow(table, values);
  }
}

template <typename Row>
std::vector<Row> ReadTable(const H5File& file, const std::string& table,
                           const std::vector<Column<Row>>& columns) {
  std::vector<Row> rows;
  for (const Column<Row>& c : columns) {
    if (c.added_later && !file.Exists(table + "/" + c.column.name)) continue;
    c.read(file, table, &rows);
  }
  return rows;
}

template <typename Row>
nlohmann::json RowJson(const Row& row, const std::vector<Column<Row>>& columns) {
  nlohmann::json out = nlohmann::json::object();
  for (const Column<Row>& c : columns) c.to_json(row, &out);
  return out;
}

void HashValue(Xxh64& h, double v) { h.Update(&v, sizeof(v)); }
void HashValue(Xxh64& h, int64_t v) { h.Update(&v, sizeof(v)); }

}  // namespace

std::string SceneFingerprint(const Scene& scene) {
  Xxh64 h;
  HashValue(h, static_cast<int64_t>(scene.views.size()));
  for (const View& v : scene.views) {
    const Intrinsics& k = v.intrinsics;
    HashValue(h, static_cast<int64_t>(k.width));
    HashValue(h, static_cast<int64_t>(k.height));
    for (double x : {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3}) HashValue(h, x);
    for (int i = 0; i < 9; ++i) HashValue(h, v.R(i / 3, i % 3));
    for (int i = 0; i < 3; ++i) HashValue(h, v.t[i]);
  }
  HashValue(h, static_cast<int64_t>(scene.points.size()));
  for (const ScenePoint& p : scene.points) {
    for (int i = 0; i < 3; ++i) HashValue(h, p.position[i]);
    HashValue(h, static_cast<int64_t>(p.observations.size()));
    for (const Observation& o : p.observations) HashValue(h, static_cast<int64_t>(o.view));
  }
  return HashHex(h.Digest());
}

namespace {

// XXH64 of everything a resume replays, so a damaged checkpoint is found before it is used.
std::string CheckpointHash(int64_t completed, const std::string& scene_fingerprint,
                           const std::string& options_fingerprint,
                           const std::vector<int64_t>& batch_offsets,
                           const std::vector<double>& positions,
                           const std::vector<int64_t>& camera_offsets,
                           const std::vector<int32_t>& cameras,
                           const std::vector<int64_t>& extensions) {
  Xxh64 hash;
  hash.Update(&completed, sizeof completed);
  hash.Update(scene_fingerprint);
  hash.Update(options_fingerprint);
  hash.Update(batch_offsets.data(), batch_offsets.size() * sizeof(int64_t));
  hash.Update(positions.data(), positions.size() * sizeof(double));
  hash.Update(camera_offsets.data(), camera_offsets.size() * sizeof(int64_t));
  hash.Update(cameras.data(), cameras.size() * sizeof(int32_t));
  // A run never extended hashes as before extensions existed.
  if (!extensions.empty()) hash.Update(extensions.data(), extensions.size() * sizeof(int64_t));
  return fmt::format("{:016x}", hash.Digest());
}

constexpr size_t kExtensionColumns = 5;

std::vector<int64_t> ExtensionRows(const std::vector<RunExtension>& extensions) {
  std::vector<int64_t> rows;
  for (const RunExtension& e : extensions) {
    rows.insert(rows.end(),
                {e.iteration, e.views_before, e.views_after, e.points_before, e.points_after});
  }
  return rows;
}

}  // namespace

int32_t RunRecord::build_views() const {
  return extensions.empty() ? static_cast<int32_t>(scene.views.size())
                            : extensions.front().views_before;
}

int64_t RunRecord::build_points() const {
  return extensions.empty() ? scene_points : extensions.front().points_before;
}

void ReleaseScenePoints(const std::string& run_file, RunRecord* record) {
  record->scene_copy_from = run_file;
  std::vector<ScenePoint>().swap(record->scene.points);
}

void StashScenePoints(const std::string& path, RunRecord* record) {
  H5File file = H5File::Create(path);
  WriteSceneH5(record->scene, file, "/scene");
  file.Commit();
  ReleaseScenePoints(path, record);
}

void WriteRunFile(const RunRecord& record, const std::string& path) {
  H5File file = H5File::Create(path);
  if (record.scene_copy_from.empty()) {
    WriteSceneH5(record.scene, file, "/scene");
  } else {
    file.CopyFrom(H5File::OpenReadOnly(record.scene_copy_from), "/scene");
  }
  file.CreateGroup("/checkpoint");
  file.SetStringAttribute("/checkpoint", "format", kRunFormat);
  file.SetIntAttribute("/checkpoint", "format_version", kRunFormatVersion);
  file.SetIntAttribute("/checkpoint", "completed_iterations", record.completed_iterations());
  file.SetStringAttribute("/checkpoint", "scene_fingerprint", record.scene_fingerprint);
  file.SetStringAttribute("/checkpoint", "options_fingerprint", record.options_fingerprint);
  file.SetStringAttribute("/checkpoint", "stop_reason", record.stop_reason);
  std::vector<int64_t> batch_offsets = {0}, camera_offsets = {0};
  std::vector<double> positions;
  std::vector<int32_t> cameras;
  for (const auto& batch : record.batches) {
    for (const RayPoint& p : batch) {
      positions.insert(positions.end(), {p.position.x(), p.position.y(), p.position.z()});
      cameras.insert(cameras.end(), p.cameras.begin(), p.cameras.end());
      camera_offsets.push_back(static_cast<int64_t>(cameras.size()));
    }
    batch_offsets.push_back(static_cast<int64_t>(camera_offsets.size() - 1));
  }
  const std::vector<int64_t> extensions = ExtensionRows(record.extensions);
  file.SetStringAttribute("/checkpoint", "content_hash",
                          CheckpointHash(record.completed_iterations(), record.scene_fingerprint,
                                         record.options_fingerprint, batch_offsets, positions,
                                         camera_offsets, cameras, extensions));
  if (!extensions.empty()) {
    file.Write("/checkpoint/extensions", extensions,
               H5Shape{record.extensions.size(), kExtensionColumns});
  }
  file.Write("/checkpoint/batch_offsets", batch_offsets);
  file.Write("/checkpoint/positions", positions, H5Shape{positions.size() / 3, 3});
  file.Write("/checkpoint/camera_offsets", camera_offsets);
  file.Write("/checkpoint/cameras", cameras);
  WriteTable(file, "/stats/iterations", IterationColumns(), record.iterations);
  WriteTable(file, "/stats/workers", WorkerColumns(), record.workers);
  file.Commit();
}

RunRecord ReadRunFile(const std::string& path) {
  const H5File file = H5File::OpenReadOnly(path);
  auto fail = [&](const std::string& what) -> void {
    throw InputError(path + ": /checkpoint: " + what);
  };
  if (!file.IsGroup("/checkpoint") || !file.HasAttribute("/checkpoint", "format") ||
      file.ReadStringAttribute("/checkpoint", "format") != kRunFormat) {
    throw InputError(path + ": not a manisweep run file (no /checkpoint of format " + kRunFormat +
                     ")");
  }
  const int64_t version = file.ReadIntAttribute("/checkpoint", "format_version");
  if (version != kRunFormatVersion) {
    fail(fmt::format("format_version {} (this build reads {})", version, kRunFormatVersion));
  }
  RunRecord record;
  record.scene = ReadSceneH5(file, "/scene");
  record.scene_points = static_cast<int64_t>(record.scene.points.size());
  record.scene_fingerprint = file.ReadStringAttribute("/checkpoint", "scene_fingerprint");
  record.options_fingerprint = file.ReadStringAttribute("/checkpoint", "options_fingerprint");
  record.stop_reason = file.ReadStringAttribute("/checkpoint", "stop_reason");
  const int64_t completed = file.ReadIntAttribute("/checkpoint", "completed_iterations");
  const auto batch_offsets = file.Read<int64_t>("/checkpoint/batch_offsets", {kH5Any});
  const auto positions = file.Read<double>("/checkpoint/positions", {kH5Any, 3});
  const auto camera_offsets = file.Read<int64_t>("/checkpoint/camera_offsets", {kH5Any});
  const auto cameras = file.Read<int32_t>("/checkpoint/cameras", {kH5Any});
  const std::vector<int64_t> extensions =
      file.IsDataset("/checkpoint/extensions")
          ? file.Read<int64_t>("/checkpoint/extensions", {kH5Any, kExtensionColumns})
          : std::vector<int64_t>();
  // Files written before the hash have none; every newer one must match it.
  if (file.HasAttribute("/checkpoint", "content_hash") &&
      file.ReadStringAttribute("/checkpoint", "content_hash") !=
          CheckpointHash(completed, record.scene_fingerprint, record.options_fingerprint,
                         batch_offsets, positions, camera_offsets, cameras, extensions)) {
    fail("its content hash does not match its data: the file is damaged");
  }
  const int64_t num_points = static_cast<int64_t>(positions.size() / 3);
  if (completed < 0 || static_cast<int64_t>(batch_offsets.size()) != completed + 1) {
    fail("batch_offsets has " + std::to_string(batch_offsets.size()) + " entries for " +
         std::to_string(completed) + " completed iterations");
  }
  if (static_cast<int64_t>(camera_offsets.size()) != num_points + 1 || camera_offsets[0] != 0 ||
      camera_offsets.back() != static_cast<int64_t>(cameras.size())) {
    fail("camera_offsets do not match positions and cameras");
  }
  if (batch_offsets[0] != 0 || batch_offsets.back() != num_points) {
    fail("batch_offsets do not cover the positions");
  }
  const int32_t num_views = static_cast<int32_t>(record.scene.views.size());
  RunExtension last;
  last.views_after = 0;
  for (size_t row = 0; row < extensions.size() / kExtensionColumns; ++row) {
    const int64_t* r = &extensions[row * kExtensionColumns];
    RunExtension e;
    e.iteration = static_cast<int32_t>(r[0]);
    e.views_before = static_cast<int32_t>(r[1]);
    e.views_after = static_cast<int32_t>(r[2]);
    e.points_before = r[3];
    e.points_after = r[4];
    const bool first = record.extensions.empty();
    if (e.iteration < 1 || e.iteration > completed || (!first && e.iteration <= last.iteration) ||
        e.views_before < 1 || e.views_after <= e.views_before || e.views_after > num_views ||
        (!first && e.views_before != last.views_after) || e.points_before < 0 ||
        e.points_after < e.points_before || e.points_after > record.scene_points ||
        (!first && e.points_before != last.points_after)) {
      fail(fmt::format("extensions row {} does not fit the scene and the iterations", row));
    }
    record.extensions.push_back(e);
    last = e;
  }
  for (int64_t b = 0; b < completed; ++b) {
    if (batch_offsets[b + 1] < batch_offsets[b]) fail("batch_offsets decrease");
    std::vector<RayPoint> batch;
    for (int64_t i = batch_offsets[b]; i < batch_offsets[b + 1]; ++i) {
      if (camera_offsets[i + 1] < camera_offsets[i]) fail("camera_offsets decrease");
      RayPoint p;
      p.position = Eigen::Vector3d(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
      for (int64_t c = camera_offsets[i]; c < camera_offsets[i + 1]; ++c) {
        if (cameras[c] < 0 || cameras[c] >= num_views) {
          fail(fmt::format("cameras[{}] = {} is not a view of the scene", c, cameras[c]));
        }
        p.cameras.push_back(cameras[c]);
      }
      batch.push_back(std::move(p));
    }
    record.batches.push_back(std::move(batch));
  }
  record.iterations = ReadTable(file, "/stats/iterations", IterationColumns());
  if (static_cast<int64_t>(record.iterations.size()) != completed + 1) {
    throw InputError(
        fmt::format("{}: /stats/iterations: {} rows for {} completed iterations (+ the "
                    "build)",
                    path, record.iterations.size(), completed));
  }
  record.workers = ReadTable(file, "/stats/workers", WorkerColumns());
  return record;
}

void WriteSummaryJson(const RunRecord& record, const RunSummaryInfo& info,
                      const std::string& path) {
  using nlohmann::json;
  json j;
  j["status"] = info.status;
  j["input"] = info.input;
  j["input_absolute"] = info.input_absolute;
  j["options"] = json::object();
  for (const auto& [key, value] : info.options) j["options"][key] = value;
  j["resumed"] = info.resumed;
  j["stop_reason"] = record.stop_reason;
  j["scene"] = {{"views", record.scene.views.size()},
                {"points", record.scene_points},
                {"fingerprint", record.scene_fingerprint}};
  j["options_fingerprint"] = record.options_fingerprint;
  j["iterations_completed"] = record.completed_iterations();
  json rows = json::array();
  const std::vector<Column<IterationStats>> columns = IterationColumns();
  for (const IterationStats& s : record.iterations) {
    json row = RowJson(s, columns);
    // Kept from summary.json's first format, which scripts read.
    row["points_discarded"] = s.discarded_conflict + s.discarded_duplicate + s.discarded_outside;
    row["points_duplicate"] = s.discarded_duplicate;
    rows.push_back(std::move(row));
  }
  j["iterations"] = rows;
  json workers = json::object();
  for (const WorkerIterationStats& w : record.workers) {
    json& entry = workers[w.worker];
    if (entry.is_null()) entry = {{"jobs", 0}, {"points", 0}, {"seconds_kernel", 0.0}};
    entry["jobs"] = entry["jobs"].get<int64_t>() + w.jobs;
    entry["points"] = entry["points"].get<int64_t>() + w.points;
    entry["seconds_kernel"] = entry["seconds_kernel"].get<double>() + w.seconds_kernel;
  }
  j["workers"] = workers;
  if (!record.iterations.empty()) {
    const IterationStats& first = record.iterations.front();
    const IterationStats& last = record.iterations.back();
    j["initial_mesh"] = {{"vertices", first.vertices}, {"faces", first.faces}};
    j["current_mesh"] = {{"vertices", last.vertices}, {"faces", last.faces}};
  }
  if (!info.final_mesh.empty()) {
    j["final_mesh"] = {{"path", info.final_mesh},
                       {"closed_manifold", info.final_is_closed_manifold},
                       {"check", info.mesh_check}};
  }
  j["seconds_this_process"] = info.seconds;
  // This process: the coordinator (reconstruct's workers are processes of their own).
  j["peak_rss_bytes_this_process"] = PeakRssBytes();
  WriteFileAtomically(
      path, [&](std::ostream& out) { out << j.dump(2) << "\n"; }, false);
}

}  // namespace ms
