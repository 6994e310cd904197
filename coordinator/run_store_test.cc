// run.h5's statistics tables and summary.json: every field survives the round trip, and files of
// the older format (without the later columns) still read.
#include "coordinator/run_store.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "base/file_util.h"
#include "scene/h5_file.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::TempDir;

// Every field of the row a value of its own (k, k + 1, ...), so that a column written from one
// field and read into another shows.
IterationStats DistinctStats(int32_t k) {
  IterationStats s;
  s.iteration = k;
  s.jobs = k + 1;
  s.jobs_bad = k + 2;
  s.jobs_requeued = k + 3;
  s.cameras_skipped = k + 4;
  s.workers = k + 5;
  s.points_found = k + 6;
  s.points_inserted = k + 7;
  s.discarded_conflict = k + 8;
  s.discarded_duplicate = k + 9;
  s.discarded_outside = k + 10;
  s.vertices = k + 11;
  s.faces = k + 12;
  s.outside_cells = k + 13;
  s.cameras_in_matter = k + 14;
  s.job_bytes = k + 15;
  s.job_max_bytes = k + 16;
  s.jobs_smoothed = k + 17;
  s.image_noise_max = k + 17.5;
  s.witness_rays = k + 18;
  s.cleanup_collapses = k + 19;
  s.cleanup_splits = k + 20;
  s.float_problems_left = k + 21;
  s.seconds_jobs = k + 22.5;
  s.seconds_sweep = k + 23.5;
  s.seconds_kernel = k + 24.5;
  s.seconds_insert = k + 25.5;
  s.seconds_insert_early = k + 26.5;
  s.seconds_extract = k + 27.5;
  s.seconds_checkpoint = k + 28.5;
  s.seconds_total = k + 29.5;
  return s;
}

void ExpectSameStats(const IterationStats& a, const IterationStats& b) {
  EXPECT_EQ(a.iteration, b.iteration);
  EXPECT_EQ(a.jobs, b.jobs);
  EXPECT_EQ(a.jobs_bad, b.jobs_bad);
  EXPECT_EQ(a.jobs_requeued, b.jobs_requeued);
  EXPECT_EQ(a.cameras_skipped, b.cameras_skipped);
  EXPECT_EQ(a.workers, b.workers);
  EXPECT_EQ(a.points_found, b.points_found);
  EXPECT_EQ(a.points_inserted, b.points_inserted);
  EXPECT_EQ(a.discarded_conflict, b.discarded_conflict);
  EXPECT_EQ(a.discarded_duplicate, b.discarded_duplicate);
  EXPECT_EQ(a.discarded_outside, b.discarded_outside);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.outside_cells, b.outside_cells);
  EXPECT_EQ(a.cameras_in_matter, b.cameras_in_matter);
  EXPECT_EQ(a.job_bytes, b.job_bytes);
  EXPECT_EQ(a.job_max_bytes, b.job_max_bytes);
  EXPECT_EQ(a.jobs_smoothed, b.jobs_smoothed);
  EXPECT_EQ(a.image_noise_max, b.image_noise_max);
  EXPECT_EQ(a.witness_rays, b.witness_rays);
  EXPECT_EQ(a.cleanup_collapses, b.cleanup_collapses);
  EXPECT_EQ(a.cleanup_splits, b.cleanup_splits);
  EXPECT_EQ(a.float_problems_left, b.float_problems_left);
  EXPECT_EQ(a.seconds_jobs, b.seconds_jobs);
  EXPECT_EQ(a.seconds_sweep, b.seconds_sweep);
  EXPECT_EQ(a.seconds_kernel, b.seconds_kernel);
  EXPECT_EQ(a.seconds_insert, b.seconds_insert);
  EXPECT_EQ(a.seconds_insert_early, b.seconds_insert_early);
  EXPECT_EQ(a.seconds_extract, b.seconds_extract);
  EXPECT_EQ(a.seconds_checkpoint, b.seconds_checkpoint);
  EXPECT_EQ(a.seconds_total, b.seconds_total);
}

RunRecord RecordWithOneIteration(const TempDir& dir) {
  RunRecord record;
  record.scene = testing::MakeSyntheticScene(dir.path().string());
  record.scene_fingerprint = SceneFingerprint(record.scene);
  record.options_fingerprint = "options";
  RayPoint p;
  p.position = Eigen::Vector3d(0.1, 0.2, 0.3);
  p.cameras = {0, 1};
  record.batches = {{p}};
  record.iterations = {DistinctStats(0), DistinctStats(100)};
  record.workers = {{1, "worker-1", 3, 40, 1.25}, {1, "worker-2", 2, 30, 0.75}};
  return record;
}

TEST(RunStore, EveryStatisticSurvivesRunH5) {
  const TempDir dir("run_store");
  const RunRecord written = RecordWithOneIteration(dir);
  const std::string path = (dir.path() / "run.h5").string();
  WriteRunFile(written, path);
  const RunRecord read = ReadRunFile(path);
  ASSERT_EQ(read.iterations.size(), written.iterations.size());
  for (size_t i = 0; i < read.iterations.size(); ++i) {
    ExpectSameStats(read.iterations[i], written.iterations[i]);
  }
  ASSERT_EQ(read.workers.size(), 2u);
  EXPECT_EQ(read.workers[1].worker, "worker-2");
  EXPECT_EQ(read.workers[1].jobs, 2);
  EXPECT_EQ(read.workers[1].points, 30);
  EXPECT_EQ(read.workers[1].seconds_kernel, 0.75);
}

// An extended run's extensions survive run.h5 (and are in its content hash); a row that does not
// fit the scene is refused, naming the dataset.
TEST(RunStore, ExtensionsSurviveRunH5AndBadRowsAreRefused) {
  const TempDir dir("run_store");
  RunRecord record = RecordWithOneIteration(dir);
  record.scene_points = static_cast<int64_t>(record.scene.points.size());
  ASSERT_GE(record.scene.views.size(), 3u);
  RunExtension e;
  e.iteration = 1;
  e.views_before = 2;
  e.views_after = 3;
  e.points_before = record.scene_points - 1;
  e.points_after = record.scene_points;
  record.extensions = {e};
  const std::string path = (dir.path() / "run.h5").string();
  WriteRunFile(record, path);
  const RunRecord read = ReadRunFile(path);
  ASSERT_EQ(read.extensions.size(), 1u);
  EXPECT_EQ(read.extensions[0].iteration, 1);
  EXPECT_EQ(read.extensions[0].views_before, 2);
  EXPECT_EQ(read.extensions[0].views_after, 3);
  EXPECT_EQ(read.extensions[0].points_before, e.points_before);
  EXPECT_EQ(read.extensions[0].points_after, e.points_after);
  EXPECT_EQ(read.build_views(), 2);
  EXPECT_EQ(read.build_points(), e.points_before);

  record.extensions[0].views_after = 99;  // more views than the scene has
  WriteRunFile(record, path);
  testing::ExpectInputError([&] { ReadRunFile(path); }, {path, "extensions row 0"});
}

// A coordinator frees the scene's points after its first checkpoint; later run files copy /scene
// from the last one, so a resume still reads the whole scene.
TEST(RunStore, ReleasedScenePointsAreCopiedFromTheLastRunFile) {
  const TempDir dir("run_store");
  RunRecord record = RecordWithOneIteration(dir);
  record.scene_points = static_cast<int64_t>(record.scene.points.size());
  ASSERT_GT(record.scene_points, 0);
  const std::string first = (dir.path() / "run.h5").string();
  const std::string second = (dir.path() / "run2.h5").string();
  WriteRunFile(record, first);
  ReleaseScenePoints(first, &record);
  EXPECT_TRUE(record.scene.points.empty());
  EXPECT_FALSE(record.scene.views.empty());  // job building still needs them
  WriteRunFile(record, second);
  const RunRecord read = ReadRunFile(second);
  EXPECT_EQ(SceneFingerprint(read.scene), record.scene_fingerprint);
  EXPECT_EQ(read.scene_points, record.scene_points);
  const std::string summary = (dir.path() / "summary.json").string();
  WriteSummaryJson(record, RunSummaryInfo{}, summary);
  const nlohmann::json json = nlohmann::json::parse(ReadFileToString(summary));
  EXPECT_EQ(json["scene"]["points"].get<int64_t>(), record.scene_points);
  // The file to copy from is gone: the error names it.
  std::filesystem::remove(first);
  testing::ExpectInputError([&] { WriteRunFile(record, second); }, {first});
}

// A fresh run stashes the scene's points before its build; its first run file copies them.
TEST(RunStore, StashedScenePointsReachTheFirstRunFile) {
  const TempDir dir("run_store");
  RunRecord record = RecordWithOneIteration(dir);
  record.scene_points = static_cast<int64_t>(record.scene.points.size());
  ASSERT_GT(record.scene_points, 0);
  const std::string stash = (dir.path() / "run.scene.h5").string();
  const std::string run = (dir.path() / "run.h5").string();
  StashScenePoints(stash, &record);
  EXPECT_TRUE(record.scene.points.empty());
  EXPECT_EQ(record.scene_copy_from, stash);
  WriteRunFile(record, run);
  const RunRecord read = ReadRunFile(run);
  EXPECT_EQ(SceneFingerprint(read.scene), record.scene_fingerprint);
  EXPECT_EQ(static_cast<int64_t>(read.scene.points.size()), record.scene_points);
}

// Takes /stats/iterations/<column> out of a written run.h5 (the dataset and its name in the
// table's 'columns' list), as a file of an older format lacks it.
void DropStatsColumn(const std::string& path, const std::string& column) {
  const std::string table = "/stats/iterations";
  const hid_t raw = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(raw, 0) << path;
  EXPECT_GE(H5Ldelete(raw, (table + "/" + column).c_str(), H5P_DEFAULT), 0) << column;
  H5Fclose(raw);
  H5File file = H5File::OpenReadWrite(path);
  std::string kept;
  std::stringstream names(file.ReadStringAttribute(table, "columns"));
  for (std::string name; std::getline(names, name, ',');) {
    if (name != column) kept += (kept.empty() ? "" : ",") + name;
  }
  file.SetStringAttribute(table, "columns", kept);
}

// A run.h5 written before the later columns existed still reads (a resume of an old run): their
// fields read as zero, every other field as written.
TEST(RunStore, RunH5WithoutTheLaterColumnsReads) {
  const TempDir dir("run_store");
  const RunRecord written = RecordWithOneIteration(dir);
  const std::string path = (dir.path() / "run.h5").string();
  WriteRunFile(written, path);
  for (const char* column : {"cameras_in_matter", "job_bytes", "job_max_bytes", "jobs_smoothed",
                             "image_noise_max", "seconds_insert_early", "witness_rays"}) {
    DropStatsColumn(path, column);
  }
  const RunRecord read = ReadRunFile(path);
  ASSERT_EQ(read.iterations.size(), written.iterations.size());
  IterationStats expected = written.iterations[1];
  expected.cameras_in_matter = 0;
  expected.job_bytes = 0;
  expected.job_max_bytes = 0;
  expected.jobs_smoothed = 0;
  expected.image_noise_max = 0;
  expected.seconds_insert_early = 0;
  expected.witness_rays = 0;
  ExpectSameStats(read.iterations[1], expected);
}

// A column of the first format is never optional: a run.h5 without it is refused with an error
// that names it.
TEST(RunStore, RunH5WithoutAFirstFormatColumnIsRefused) {
  const TempDir dir("run_store");
  const std::string path = (dir.path() / "run.h5").string();
  WriteRunFile(RecordWithOneIteration(dir), path);
  DropStatsColumn(path, "vertices");
  testing::ExpectInputError([&] { ReadRunFile(path); }, {"/stats/iterations", "vertices"});
}

TEST(RunStore, SummaryJsonHasEveryColumnAndTheTotals) {
  const TempDir dir("run_store");
  const RunRecord record = RecordWithOneIteration(dir);
  const std::string path = (dir.path() / "summary.json").string();
  RunSummaryInfo info;
  info.status = "finished";
  WriteSummaryJson(record, info, path);
  const nlohmann::json j = nlohmann::json::parse(ReadFileToString(path));
  const nlohmann::json& row = j["iterations"][1];
  EXPECT_EQ(row["discarded_outside"], 110);
  EXPECT_EQ(row["seconds_insert_early"], 126.5);
  EXPECT_EQ(row["points_discarded"], 108 + 109 + 110);
  EXPECT_EQ(row["points_duplicate"], 109);
  EXPECT_EQ(row.size(), 31u + 2u);  // every column, and the two totals
  EXPECT_EQ(j["workers"]["worker-1"]["points"], 40);
}

}  // namespace
}  // namespace ms
