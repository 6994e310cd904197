// The run's steps without a transport: prepare, integrate, checkpoint, resume by replay, finish.
#include "coordinator/run_lifecycle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>

#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "proto/wire.h"
#include "scene/scene_io.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::ExpectInputError;
using testing::TempDir;

// A point on a sphere of radius 0.4 around the origin, direction (theta, phi).
Eigen::Vector3d OnSphere(double theta, double phi) {
  return 0.4 * Eigen::Vector3d(std::cos(theta) * std::cos(phi), std::sin(theta) * std::cos(phi),
                               std::sin(phi));
}

// The cameras that see p: in front, projecting inside the image, facing the sphere's outside.
std::vector<int32_t> CamerasSeeing(const Scene& scene, const Eigen::Vector3d& p) {
  std::vector<int32_t> cameras;
  for (size_t v = 0; v < scene.views.size(); ++v) {
    Eigen::Vector2d px;
    const Eigen::Vector3d to_camera = scene.views[v].Center() - p;
    if (scene.views[v].Project(p, &px) && p.dot(to_camera) > 0) {
      cameras.push_back(static_cast<int32_t>(v));
    }
  }
  return cameras;
}

// The three views of MakeSyntheticScene looking at the side of a sphere that faces them; with
// `camera_inside`, a fourth view from the sphere's centre that sees none of its points.
std::string WriteSphereScene(const TempDir& dir, bool camera_inside = false) {
  Scene scene = testing::MakeSyntheticScene(dir.path().string());
  scene.points.clear();
  if (camera_inside) {
    View inside = scene.views.front();
    inside.t = -inside.R * Eigen::Vector3d(0.01, -0.02, 0.03);
    inside.name = "inside.png";
    scene.views.push_back(inside);
  }
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 8; ++j) {
      const Eigen::Vector3d p = OnSphere(-0.6 + 0.2 * i, -0.7 + 0.2 * j);
      ScenePoint point;
      point.position = p;
      for (int32_t v : CamerasSeeing(scene, p)) {
        Eigen::Vector2d px;
        scene.views[v].Project(p, &px);
        point.observations.push_back({v, static_cast<float>(px.x()), static_cast<float>(px.y())});
      }
      if (point.observations.size() >= 2) scene.points.push_back(point);
    }
  }
  const std::string path = dir / "scene.h5";
  WriteScene(scene, path, SceneFormat::kAuto);
  return path;
}

// New points between the scene's, as a worker of camera `camera` would return them.
InsertionBatch Batch(const std::string& scene_path, double shift) {
  const Scene scene = ReadScene(scene_path);
  InsertionBatch batch;
  for (int camera = 0; camera < 3; ++camera) {
    std::vector<FoundPoint> points;
    for (int i = 0; i < 5; ++i) {
      FoundPoint f;
      f.camera = camera;
      f.position = OnSphere(-0.5 + 0.2 * i + 0.07 * camera + shift, -0.4 + 0.3 * shift);
      f.pixel_x = static_cast<float>(i);
      for (int32_t c : CamerasSeeing(scene, f.position)) {
        if (c != camera) f.cameras.push_back(c);
      }
      f.cameras.insert(f.cameras.begin(), camera);
      points.push_back(f);
    }
    batch.Add(uint64_t{1} << 32 | static_cast<uint64_t>(camera), points);
  }
  return batch;
}

CoordinatorOptions Options(const std::string& scene, const std::string& output) {
  CoordinatorOptions options;
  options.input = scene;
  options.output_dir = output;
  options.run.max_iterations = 2;
  return options;
}

TEST(RunLifecycle, ResumingReplaysTheCheckpointToTheSameMesh) {
  const TempDir dir("lifecycle");
  const std::string scene = WriteSphereScene(dir);
  const CoordinatorOptions options = Options(scene, dir / "run");

  RunLifecycle run(options, 42);
  const StepOutcome first = run.Prepare();
  ASSERT_FALSE(first.stop);
  const std::vector<wire::Job> first_jobs = first.jobs->BuildAll();
  ASSERT_FALSE(first_jobs.empty());
  EXPECT_EQ(first_jobs.front().session_id(), 42u);
  EXPECT_EQ(run.completed_iterations(), 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "run/initial.ply"));
  EXPECT_TRUE(std::filesystem::exists(dir / "run/run.h5"));
  // The scene's points waited in a stash during the build; run.h5 holds them now.
  EXPECT_FALSE(
      std::filesystem::exists(std::filesystem::path(dir / "run") / RunLifecycle::kSceneStash));
  const size_t initial_vertices = run.surface().NumVertices();

  SweepRound round;
  round.jobs = static_cast<int32_t>(first_jobs.size());
  round.jobs_by_worker["w1"] = round.jobs;
  const StepOutcome second = run.Integrate(Batch(scene, 0.0).Sorted(), round);
  ASSERT_FALSE(second.stop);
  run.WaitForCheckpoint();  // written in the background while the next sweep would run
  EXPECT_EQ(run.completed_iterations(), 1);
  EXPECT_GT(run.surface().NumVertices(), initial_vertices) << "no point of the batch was inserted";
  const Mesh after_one = run.surface();

  // A coordinator restarted after iteration 1 rebuilds exactly that mesh.
  CoordinatorOptions resume = options;
  resume.run.resume = true;
  RunLifecycle resumed(resume, 43);
  const StepOutcome again = resumed.Prepare();
  ASSERT_FALSE(again.stop);
  EXPECT_EQ(resumed.completed_iterations(), 1);
  EXPECT_EQ(resumed.surface().vertices, after_one.vertices);
  EXPECT_EQ(resumed.surface().faces, after_one.faces);
  const std::vector<wire::Job> again_jobs = again.jobs->BuildAll();
  ASSERT_FALSE(again_jobs.empty());
  EXPECT_EQ(again_jobs.front().session_id(), 43u);
  EXPECT_EQ(again_jobs.front().iteration(), 2u);

  // Iteration 2 reaches --max-iterations: the run finishes with a closed manifold.
  const StepOutcome last = resumed.Integrate(Batch(scene, 0.1).Sorted(), round);
  EXPECT_TRUE(last.stop);
  EXPECT_EQ(resumed.final_result().stop_reason, "reached --max-iterations 2");
  EXPECT_TRUE(resumed.final_result().final_is_closed_manifold);
  const MeshReport report = CheckMesh(ReadMesh(dir / "run/final.ply"));
  EXPECT_TRUE(report.is_closed_manifold);
}

// A run that stops before its first checkpoint (here: no cell is free space) says why and leaves
// no stash of the scene's points behind.
TEST(RunLifecycle, ARunStoppedBeforeItsFirstCheckpointLeavesNoStash) {
  const TempDir dir("lifecycle");
  CoordinatorOptions options = Options(WriteSphereScene(dir), dir / "run");
  options.manifold.free_threshold = 1e9;
  {
    RunLifecycle run(options, 7);
    ExpectInputError([&] { run.Prepare(); }, {"initial manifold is empty"});
  }
  EXPECT_FALSE(
      std::filesystem::exists(std::filesystem::path(dir / "run") / RunLifecycle::kSceneStash));
  EXPECT_FALSE(std::filesystem::exists(dir / "run/run.h5"));
}

// The coordinator inserts the points of cameras whose results are in while the sweep goes on:
// the iteration must come out exactly as when the whole batch is inserted at the end, checkpoint
// included (a resumed run replays the batch whole).
TEST(RunLifecycle, InsertingDuringTheSweepGivesTheSameIteration) {
  const TempDir dir("lifecycle");
  const std::string scene_file = WriteSphereScene(dir);
  const std::vector<RayPoint> batch = Batch(scene_file, 0.0).Sorted();
  ASSERT_GT(batch.size(), 10u);
  SweepRound round;
  round.jobs = 1;

  RunLifecycle at_end(Options(scene_file, dir / "at_end"), 1);
  ASSERT_FALSE(at_end.Prepare().stop);
  at_end.Integrate(batch, round);

  RunLifecycle early(Options(scene_file, dir / "early"), 1);
  ASSERT_FALSE(early.Prepare().stop);
  const auto cut = [&](size_t a, size_t b) {
    return std::vector<RayPoint>(batch.begin() + static_cast<std::ptrdiff_t>(a),
                                 batch.begin() + static_cast<std::ptrdiff_t>(b));
  };
  early.InsertEarly(cut(0, 3));
  early.InsertEarly(cut(3, batch.size() / 2));
  early.Integrate(cut(batch.size() / 2, batch.size()), round);
  at_end.WaitForCheckpoint();
  early.WaitForCheckpoint();

  EXPECT_EQ(early.surface().vertices, at_end.surface().vertices);
  EXPECT_EQ(early.surface().faces, at_end.surface().faces);
  const RunRecord a = ReadRunFile(dir / "at_end/run.h5");
  const RunRecord b = ReadRunFile(dir / "early/run.h5");
  ASSERT_EQ(b.batches.size(), 1u);
  ASSERT_EQ(b.batches[0].size(), a.batches[0].size());
  for (size_t i = 0; i < a.batches[0].size(); ++i) {
    EXPECT_EQ(b.batches[0][i].position, a.batches[0][i].position);
  }
  EXPECT_EQ(b.iterations[1].points_inserted, a.iterations[1].points_inserted);
  EXPECT_GT(b.iterations[1].seconds_insert_early, 0);
  EXPECT_EQ(a.iterations[1].seconds_insert_early, 0);
}

TEST(RunLifecycle, AnExistingRunIsNeverOverwrittenOrResumedWithOtherOptions) {
  const TempDir dir("lifecycle");
  const std::string scene = WriteSphereScene(dir);
  const CoordinatorOptions options = Options(scene, dir / "run");
  RunLifecycle(options, 1).Prepare();

  ExpectInputError([&] { RunLifecycle(options, 2).Prepare(); },
                   {"holds a run already", "--resume"});
  CoordinatorOptions other = options;
  other.run.resume = true;
  other.manifold.w1 = 5;
  ExpectInputError([&] { RunLifecycle(other, 3).Prepare(); }, {"run.h5", "other options"});
}

// The checkpoint written during the next sweep: its failure (a full disk) must still stop the
// run, and the one before stays in place.
TEST(RunLifecycle, ABackgroundCheckpointThatFailsIsReported) {
  const TempDir dir("lifecycle");
  const std::string scene = WriteSphereScene(dir);
  RunLifecycle run(Options(scene, dir / "run"), 1);
  ASSERT_FALSE(run.Prepare().stop);
  // run.h5 cannot be replaced: a directory that is not empty stands in its way.
  std::filesystem::rename(dir / "run/run.h5", dir / "run/kept.h5");
  std::filesystem::create_directory(dir / "run/run.h5");
  std::ofstream(dir / "run/run.h5/blocker") << "x";
  SweepRound round;
  round.jobs = 3;
  const StepOutcome next = run.Integrate(Batch(scene, 0.0).Sorted(), round);
  ASSERT_FALSE(next.stop);
  bool reported = false;
  try {
    run.WaitForCheckpoint();
  } catch (const std::exception& e) {
    reported = true;
    EXPECT_THAT(e.what(), ::testing::HasSubstr("run.h5"));
  }
  EXPECT_TRUE(reported) << "the failed checkpoint went unnoticed";
  EXPECT_NO_THROW(run.WaitForCheckpoint()) << "reported once";
  EXPECT_EQ(ReadRunFile(dir / "run/kept.h5").completed_iterations(), 0);
}

// A camera inside the matter is counted in every row of run.h5 (and warned about).
TEST(RunLifecycle, CamerasInTheMatterAreCountedPerIteration) {
  const TempDir dir("lifecycle");
  const std::string scene = WriteSphereScene(dir, /*camera_inside=*/true);
  RunLifecycle run(Options(scene, dir / "run"), 1);
  ASSERT_FALSE(run.Prepare().stop);
  SweepRound round;
  run.Integrate(Batch(scene, 0.0).Sorted(), round);
  run.WaitForCheckpoint();
  const RunRecord record = ReadRunFile(dir / "run/run.h5");
  ASSERT_EQ(record.iterations.size(), 2u);
  EXPECT_EQ(record.iterations[0].cameras_in_matter, 1);
  EXPECT_EQ(record.iterations[1].cameras_in_matter, 1);
}

TEST(RunLifecycle, ABatchWithNothingNewEndsTheRun) {
  const TempDir dir("lifecycle");
  const std::string scene = WriteSphereScene(dir);
  RunLifecycle run(Options(scene, dir / "run"), 1);
  ASSERT_FALSE(run.Prepare().stop);
  const StepOutcome outcome = run.Integrate({}, SweepRound());
  EXPECT_TRUE(outcome.stop);
  EXPECT_EQ(run.final_result().stop_reason, "converged: no new point was inserted");
  EXPECT_TRUE(std::filesystem::exists(dir / "run/final.ply"));
}

// A run that stops before its first iteration writes its final meshes from the manifold it
// built: the initial meshes took the extracted surface, so it is extracted again, the same.
TEST(RunLifecycle, ARunStoppedBeforeItsFirstIterationWritesTheInitialMeshAsFinal) {
  const TempDir dir("lifecycle");
  CoordinatorOptions options = Options(WriteSphereScene(dir), dir / "run");
  options.run.max_iterations = 0;
  RunLifecycle run(options, 1);
  EXPECT_TRUE(run.Prepare().stop);
  EXPECT_EQ(run.final_result().stop_reason, "reached --max-iterations 0");
  const Mesh initial = ReadMesh(dir / "run/initial.ply");
  const Mesh final_mesh = ReadMesh(dir / "run/final.ply");
  EXPECT_GT(initial.NumFaces(), 0u);
  EXPECT_EQ(final_mesh.vertices, initial.vertices);
  EXPECT_EQ(final_mesh.faces, initial.faces);
}

// The sphere scene's first `views` cameras and the points at least `min_track` of them see.
std::string WriteFirstViews(const TempDir& dir, const std::string& full, int views,
                            size_t min_track = 2) {
  Scene scene = ReadScene(full);
  scene.views.resize(views);
  std::vector<ScenePoint> kept;
  for (ScenePoint p : scene.points) {
    p.observations.erase(std::remove_if(p.observations.begin(), p.observations.end(),
                                        [&](const Observation& o) { return o.view >= views; }),
                         p.observations.end());
    if (p.observations.size() >= min_track) kept.push_back(p);
  }
  scene.points = kept;
  const std::string path = dir / ("first" + std::to_string(views) + ".h5");
  WriteScene(scene, path, SceneFormat::kAuto);
  return path;
}

// A finished run of the first two cameras (no sweep point: it converges after the build).
CoordinatorOptions FinishedFirstRun(const TempDir& dir, const std::string& full) {
  CoordinatorOptions options = Options(WriteFirstViews(dir, full, 2), dir / "run");
  RunLifecycle run(options, 1);
  EXPECT_FALSE(run.Prepare().stop);
  EXPECT_TRUE(run.Integrate({}, SweepRound()).stop);
  return options;
}

std::string FileBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(RunLifecycle, AnExtensionInsertsTheNewCamerasPointsThenSweepsThem) {
  const TempDir dir("lifecycle");
  const std::string full = WriteSphereScene(dir);
  FinishedFirstRun(dir, full);
  const std::string run_bytes = FileBytes(dir / "run/run.h5");

  CoordinatorOptions extend = Options(full, dir / "extended");
  extend.extend_run = dir / "run";
  extend.run.max_iterations = 1;
  RunLifecycle extended(extend, 2);
  const StepOutcome next = extended.Prepare();
  ASSERT_FALSE(next.stop);
  // The run's iteration, then the extension's insertion.
  EXPECT_EQ(extended.completed_iterations(), 2);
  EXPECT_EQ(extended.num_views(), 3);
  const RunRecord record = ReadRunFile(dir / "extended/run.h5");
  ASSERT_EQ(record.extensions.size(), 1u);
  const RunExtension& e = record.extensions[0];
  EXPECT_EQ(e.iteration, 2);
  EXPECT_EQ(e.views_before, 2);
  EXPECT_EQ(e.views_after, 3);
  EXPECT_GT(e.points_after, e.points_before);
  const IterationStats& row = record.iterations[2];
  EXPECT_EQ(row.points_found, e.points_after - e.points_before);
  EXPECT_GT(row.points_inserted, 0);      // the points only the new camera shares
  EXPECT_GT(row.discarded_duplicate, 0);  // the old points it sees too
  EXPECT_EQ(row.cameras_in_matter, 0);
  // The new camera is swept (with its neighbours).
  const std::vector<uint64_t>& ids = next.jobs->job_ids();
  EXPECT_NE(std::find(ids.begin(), ids.end(), MakeJobId(3, 2)), ids.end());

  // Resumed after the extension: the same manifold, replayed with the camera added in place.
  CoordinatorOptions resume = extend;
  resume.run.resume = true;
  RunLifecycle resumed(resume, 3);
  ASSERT_FALSE(resumed.Prepare().stop);
  EXPECT_EQ(resumed.surface().vertices, extended.surface().vertices);
  EXPECT_EQ(resumed.surface().faces, extended.surface().faces);
  // One sweep iteration, as --max-iterations says for the extension, then a closed manifold.
  const StepOutcome last = resumed.Integrate(Batch(full, 0.0).Sorted(), SweepRound());
  EXPECT_TRUE(last.stop);
  EXPECT_EQ(resumed.final_result().stop_reason, "reached --max-iterations 1");
  EXPECT_TRUE(CheckMesh(ReadMesh(dir / "extended/final.ply")).is_closed_manifold);
  EXPECT_EQ(FileBytes(dir / "run/run.h5"), run_bytes) << "the extended run was modified";
}

// An extended run extended again: one camera, then the second, then the third. A resume of the
// last replays both extensions, each rebuilding the manifold with its cameras and points.
TEST(RunLifecycle, AnExtendedRunExtendsAgainAndResumes) {
  const TempDir dir("lifecycle");
  const std::string full = WriteSphereScene(dir);
  // One camera's Steiner box does not hold the others: the rebuilt manifold's box does.
  CoordinatorOptions first = Options(WriteFirstViews(dir, full, 1, 1), dir / "one");
  {
    // One camera has no neighbour: the run ends after its build.
    RunLifecycle one(first, 1);
    EXPECT_TRUE(one.Prepare().stop);
  }
  CoordinatorOptions second = first;
  second.input = WriteFirstViews(dir, full, 2);
  second.output_dir = dir / "two";
  second.extend_run = dir / "one";
  {
    RunLifecycle two(second, 2);
    const StepOutcome next = two.Prepare();
    ASSERT_FALSE(next.stop);
    EXPECT_TRUE(two.Integrate({}, SweepRound()).stop);
  }
  CoordinatorOptions third = first;
  third.input = full;
  third.output_dir = dir / "three";
  third.extend_run = dir / "two";
  RunLifecycle three(third, 3);
  ASSERT_FALSE(three.Prepare().stop);
  const RunRecord record = ReadRunFile(dir / "three/run.h5");
  ASSERT_EQ(record.extensions.size(), 2u);
  EXPECT_EQ(record.extensions[0].views_before, 1);
  EXPECT_EQ(record.extensions[1].views_before, 2);
  EXPECT_EQ(record.extensions[1].views_after, 3);
  EXPECT_EQ(record.build_views(), 1);

  CoordinatorOptions resume = third;
  resume.run.resume = true;
  RunLifecycle resumed(resume, 4);
  ASSERT_FALSE(resumed.Prepare().stop);
  EXPECT_EQ(resumed.surface().vertices, three.surface().vertices);
  EXPECT_EQ(resumed.surface().faces, three.surface().faces);
}

TEST(RunLifecycle, AnExtensionIsRefusedWithOneLineAndTheRunKept) {
  const TempDir dir("lifecycle");
  const std::string full = WriteSphereScene(dir);
  const CoordinatorOptions first = FinishedFirstRun(dir, full);
  const std::string run_bytes = FileBytes(dir / "run/run.h5");
  const auto model = [&](const std::function<void(Scene*)>& change) {
    Scene scene = ReadScene(full);
    change(&scene);
    const std::string path = dir / "model.h5";
    WriteScene(scene, path, SceneFormat::kAuto);
    return path;
  };
  const auto extend = [&](const std::string& input, const std::string& output) {
    CoordinatorOptions options = Options(input, output);
    options.extend_run = dir / "run";
    RunLifecycle(options, 9).Prepare();
  };
  const std::string moved = model(
      [](Scene* s) { s->views[1].SetCenter(s->views[1].Center() + Eigen::Vector3d(0.3, 0, 0)); });
  ExpectInputError([&] { extend(moved, dir / "out1"); },
                   {"model.h5", "camera 1", "moved by 0.3", "--extend.max-camera-shift"});
  const std::string missing = model([](Scene* s) { s->views[0].name = "another.png"; });
  ExpectInputError([&] { extend(missing, dir / "out2"); }, {"is not in the model"});
  ExpectInputError([&] { extend(first.input, dir / "out3"); }, {"no new image"});
  ExpectInputError([&] { extend(full, dir / "run"); }, {"another folder"});
  CoordinatorOptions other = Options(full, dir / "out4");
  other.extend_run = dir / "run";
  other.manifold.w1 = 5;
  ExpectInputError([&] { RunLifecycle(other, 9).Prepare(); }, {"other options"});
  for (const char* out : {"out1", "out2", "out3", "out4"}) {
    EXPECT_FALSE(std::filesystem::exists(std::filesystem::path(dir / out) / "run.h5")) << out;
  }
  EXPECT_EQ(FileBytes(dir / "run/run.h5"), run_bytes);

  // A run not yet finished is not extended.
  CoordinatorOptions unfinished = Options(first.input, dir / "running");
  RunLifecycle(unfinished, 1).Prepare();
  CoordinatorOptions options = Options(full, dir / "out5");
  options.extend_run = dir / "running";
  ExpectInputError([&] { RunLifecycle(options, 9).Prepare(); }, {"has not finished"});
}

}  // namespace
}  // namespace ms
