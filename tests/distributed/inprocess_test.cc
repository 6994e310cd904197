// The coordinator and workers in one process, over the in-memory transport: the whole protocol
// and the iteration loop without sockets (the multi-process test does the same with sockets).
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <thread>

#include "base/error.h"
#include "base/file_util.h"
#include "coordinator/coordinator.h"
#include "coordinator/run_store.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "scene/h5_file.h"
#include "sweep/sweep_kernel_factory.h"
#include "testing/in_memory_network.h"
#include "tests/distributed/pyramid_scene_files.h"
#include "worker/job_codec.h"
#include "worker/worker_process.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

// A rogue or buggy worker: the real sweep, then every point moved 5 cm sideways, off the ray of
// the pixel it reports (inside the scene's box, so only the check against the job catches it).
class OffRayKernel : public SweepKernel {
 public:
  explicit OffRayKernel(std::unique_ptr<SweepKernel> real) : real_(std::move(real)) {}
  SweepResult Run(const SweepJob& job) override {
    SweepResult result = real_->Run(job);
    for (SweepPoint& p : result.points) p.position.x() += 0.05;
    return result;
  }
  std::string Name() const override { return real_->Name(); }

 private:
  std::unique_ptr<SweepKernel> real_;
};

class InProcessRun : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) / ("manisweep_inprocess_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    testing::PyramidSceneFileOptions options;
    options.width = 160;
    options.height = 120;
    scene_ = testing::WritePyramidSceneFiles((root_ / "scene").string(), options);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(root_);
  }

  // Runs to the end with `workers` worker threads; `junk` is sent first by a rogue client, and
  // `rogues` more workers return points that no sweep of their job could find.
  CoordinatorResult Run(const std::string& name, int workers,
                        const std::vector<std::string>& junk = {}, int rogues = 0,
                        bool resume = false) {
    auto network = InMemoryNetwork::Create();
    auto server = network->Bind();
    CoordinatorOptions options;
    options.input = scene_;
    options.output_dir = (root_ / name).string();
    options.run.max_iterations = 2;
    options.run.resume = resume;
    options.scheduler.heartbeat_interval_s = 0.05;
    options.scheduler.liveness = 4;
    options.sweep.tile_size_px = 10;
    options.sweep.gaussian_sigma_px = 4;
    auto rogue = network->Connect();
    for (const std::string& message : junk) rogue->Send(message);
    // Workers end with the coordinator's Shutdown; the flag only unblocks a broken test.
    std::atomic<bool> stop{false};
    std::vector<std::thread> threads;
    for (int i = 0; i < workers + rogues; ++i) {
      threads.emplace_back([&, i] {
        const bool rogue = i >= workers;
        WorkerOptions w;
        w.id = (rogue ? "rogue-" : "thread-") + std::to_string(i);
        w.heartbeat_interval_s = 0.05;
        w.liveness = 4;
        w.cache.directory = (root_ / "cache").string();
        std::unique_ptr<SweepKernel> kernel = MakeSweepKernel("reference");
        if (rogue) kernel = std::make_unique<OffRayKernel>(std::move(kernel));
        Worker worker(
            w, [network] { return network->Connect(); }, std::move(kernel));
        const WorkerSummary summary = worker.Run([&] { return stop.load(); });
        EXPECT_EQ(summary.exit_reason, rogue
                                           ? "shutdown: its results do not fit the jobs handed out"
                                           : "shutdown: the run is complete");
      });
    }
    Coordinator coordinator(options, server.get());
    const CoordinatorResult result = coordinator.Run({});
    std::thread watchdog([&] {
      for (int i = 0; i < 500 && !stop; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      stop = true;
    });
    for (std::thread& t : threads) t.join();
    stop = true;
    watchdog.join();
    return result;
  }

  fs::path root_;
  std::string scene_;
};

TEST_F(InProcessRun, ConvergesToTheSameClosedManifoldWithOneOrTwoWorkers) {
  const CoordinatorResult one = Run("one", 1);
  EXPECT_EQ(one.status, "finished");
  EXPECT_EQ(one.iterations, 2);
  EXPECT_TRUE(one.final_is_closed_manifold);
  const CoordinatorResult two =
      Run("two", 2, {"", "\x08\x01 junk", std::string(1000, '\xff')});  // junk never crashes it
  EXPECT_EQ(ReadFileToString(one.final_mesh), ReadFileToString(two.final_mesh));
  const MeshReport report = CheckMesh(ReadMesh(two.final_mesh));
  EXPECT_TRUE(report.is_closed_manifold) << report.ToTable();
  const RunRecord record = ReadRunFile((root_ / "two" / "run.h5").string());
  ASSERT_EQ(record.batches.size(), 2u);
  EXPECT_GT(record.batches[0].size(), 100u);
  // The batch is in insertion order: by camera first.
  for (size_t i = 1; i < record.batches[0].size(); ++i) {
    EXPECT_LE(record.batches[0][i - 1].cameras[0], record.batches[0][i].cameras[0]);
  }
}

TEST_F(InProcessRun, AWorkerWhosePointsDoNotFitItsJobsIsSentAway) {
  const CoordinatorResult honest = Run("honest", 1);
  const CoordinatorResult mixed = Run("mixed", 1, {}, /*rogues=*/1);
  EXPECT_EQ(mixed.status, "finished");
  EXPECT_EQ(ReadFileToString(honest.final_mesh), ReadFileToString(mixed.final_mesh));
}

// A damaged checkpoint (truncated, or with data that no longer matches its content hash) is
// reported and the run resumes from the previous one, to the same mesh; with both damaged the
// error names both.
TEST_F(InProcessRun, ADamagedCheckpointResumesFromThePreviousOne) {
  const CoordinatorResult clean = Run("clean", 1);
  const fs::path dir = root_ / "clean";
  ASSERT_TRUE(fs::exists(dir / "run.prev.h5"));
  const std::string mesh = ReadFileToString(clean.final_mesh);
  // Truncated at half its size.
  fs::resize_file(dir / "run.h5", fs::file_size(dir / "run.h5") / 2);
  const CoordinatorResult truncated = Run("clean", 1, {}, 0, /*resume=*/true);
  EXPECT_EQ(truncated.status, "finished");
  EXPECT_EQ(ReadFileToString(truncated.final_mesh), mesh);
  EXPECT_TRUE(fs::exists(dir / "run.damaged.h5"));
  // One point moved inside the file, its hash left as it was.
  {
    H5File file = H5File::OpenReadWrite((dir / "run.h5").string());
    std::vector<double> positions = file.Read<double>("/checkpoint/positions", {kH5Any, 3});
    ASSERT_FALSE(positions.empty());
    positions[0] += 1e-3;
    file.Write("/checkpoint/positions", positions, H5Shape{positions.size() / 3, 3});
  }
  const CoordinatorResult altered = Run("clean", 1, {}, 0, /*resume=*/true);
  EXPECT_EQ(ReadFileToString(altered.final_mesh), mesh);
  // Both damaged: one error naming both.
  fs::resize_file(dir / "run.h5", 100);
  fs::resize_file(dir / "run.prev.h5", 100);
  auto network = InMemoryNetwork::Create();
  auto server = network->Bind();
  CoordinatorOptions options;
  options.output_dir = dir.string();
  options.run.resume = true;
  Coordinator coordinator(options, server.get());
  try {
    coordinator.Run({});
    ADD_FAILURE() << "resumed from two damaged checkpoints";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("run.h5"), std::string::npos) << what;
    EXPECT_NE(what.find("run.prev.h5"), std::string::npos) << what;
  }
}

// The same over the whole file: truncated at, or with a byte flipped at, 24 offsets spread over
// it. Every resume either reads run.h5 (a flip in bytes nothing reads) or falls back to
// run.prev.h5, and ends with the undisturbed mesh; none crashes or accepts damaged data.
TEST_F(InProcessRun, ACheckpointDamagedAtAnyOffsetNeverChangesTheResult) {
  const CoordinatorResult clean = Run("any", 1);
  const fs::path dir = root_ / "any";
  const std::string mesh = ReadFileToString(clean.final_mesh);
  const std::string good = ReadFileToString(dir / "run.h5");
  const std::string previous = ReadFileToString(dir / "run.prev.h5");
  int fell_back = 0;
  for (int trial = 0; trial < 48; ++trial) {
    const size_t offset = (trial / 2) * good.size() / 24 + 7;
    std::string damaged = good;
    if (trial % 2 == 0) {
      damaged.resize(offset);
    } else {
      damaged[offset] = static_cast<char>(damaged[offset] ^ 0x5a);
    }
    WriteFileAtomically(dir / "run.h5", [&](std::ostream& out) { out << damaged; });
    WriteFileAtomically(dir / "run.prev.h5", [&](std::ostream& out) { out << previous; });
    fs::remove(dir / "run.damaged.h5");
    const CoordinatorResult resumed = Run("any", 1, {}, 0, /*resume=*/true);
    ASSERT_EQ(resumed.status, "finished") << "trial " << trial;
    ASSERT_EQ(ReadFileToString(resumed.final_mesh), mesh) << "trial " << trial;
    fell_back += fs::exists(dir / "run.damaged.h5");
  }
  std::printf("48 damaged checkpoints: %d fell back to run.prev.h5, %d read run.h5\n", fell_back,
              48 - fell_back);
  EXPECT_GE(fell_back, 24);  // every truncation at least
}

TEST_F(InProcessRun, ChangedOptionsCannotResumeARun) {
  Run("first", 1);
  auto network = InMemoryNetwork::Create();
  auto server = network->Bind();
  CoordinatorOptions options;
  options.output_dir = (root_ / "first").string();
  options.run.resume = true;
  options.manifold.w1 = 3.0;  // differs from the checkpoint
  Coordinator coordinator(options, server.get());
  try {
    coordinator.Run({});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("other options"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ms
