// Refinement's gradients on workers (coordinator/refine_dispatcher.h) in one process, over the
// in-memory transport: real workers give exactly the sums this process computes, a worker whose
// gradients do not fit its jobs is sent away without changing them, and a stop ends a round.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <thread>

#include "coordinator/refine_dispatcher.h"
#include "mesh/mesh_io.h"
#include "proto/wire.h"
#include "refine/gradient_kernel.h"
#include "refine/refiner.h"
#include "scene/scene_io.h"
#include "sweep/sweep_images.h"
#include "sweep/sweep_kernel_factory.h"
#include "testing/in_memory_network.h"
#include "tests/distributed/pyramid_scene_files.h"
#include "worker/worker_process.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

constexpr int kLevel = 1;

class RefineDispatch : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) / ("manisweep_refine_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    testing::PyramidSceneFileOptions options;
    options.width = 160;
    options.height = 120;
    const std::string path = testing::WritePyramidSceneFiles((root_ / "scene").string(), options);
    scene_ = ReadScene(path);
    // The true surface, its apex lowered: a mesh the cameras see, with a gradient to find.
    mesh_ = ReadMesh((root_ / "scene" / "gt.ply").string());
    size_t apex = 0;
    for (size_t v = 0; v < mesh_.vertices.size(); ++v) {
      if (mesh_.vertices[v].z() > mesh_.vertices[apex].z()) apex = v;
    }
    mesh_.vertices[apex].z() *= 0.8;
    pairs_ = RefinePairs(scene_, NeighbourOptions());
    ASSERT_FALSE(pairs_.empty());
    options_.gaussian_sigma_px = 1.5;
    scheduler_.heartbeat_interval_s = 0.05;
    scheduler_.liveness = 10;
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(root_);
  }

  // What `manisweep refine` computes in this process.
  std::vector<PairGradient> Local() const {
    std::vector<PairGradient> out;
    const std::unique_ptr<PairGradientKernel> kernel = MakePairGradientKernel(options_.kernel);
    for (const auto& [a, b] : pairs_) {
      const RefineView reference = RefineViewAtLevel(LoadSweepCamera(a, scene_.views[a]), kLevel);
      const RefineView neighbour = RefineViewAtLevel(LoadSweepCamera(b, scene_.views[b]), kLevel);
      out.push_back(kernel->Compute(mesh_, reference, neighbour, options_));
    }
    return out;
  }

  std::thread StartWorker(const std::shared_ptr<InMemoryNetwork>& network, int i,
                          std::atomic<bool>* stop, std::string* exit_reason) {
    return std::thread([=] {
      WorkerOptions w;
      w.id = "thread-" + std::to_string(i);
      w.heartbeat_interval_s = 0.05;
      w.liveness = 10;
      w.cache.directory = (root_ / "cache").string();
      Worker worker(
          w, [network] { return network->Connect(); }, MakeSweepKernel("reference"));
      *exit_reason = worker.Run([stop] { return stop->load(); }).exit_reason;
    });
  }

  static void ExpectSame(const std::vector<PairGradient>& a, const std::vector<PairGradient>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (size_t p = 0; p < a.size(); ++p) {
      EXPECT_EQ(a[p].energy, b[p].energy) << "pair " << p;
      EXPECT_EQ(a[p].pixels, b[p].pixels) << "pair " << p;
      ASSERT_EQ(a[p].gradient.size(), b[p].gradient.size());
      for (size_t v = 0; v < a[p].gradient.size(); ++v) {
        EXPECT_EQ(a[p].gradient[v], b[p].gradient[v]) << "pair " << p << " vertex " << v;
        EXPECT_EQ(a[p].parallax_rate2[v], b[p].parallax_rate2[v]);
        EXPECT_EQ(a[p].weight[v], b[p].weight[v]);
      }
    }
  }

  fs::path root_;
  Scene scene_;
  Mesh mesh_;
  std::vector<std::pair<int, int>> pairs_;
  RefineOptions options_;
  SchedulerOptions scheduler_;
};

// A rogue worker: answers every job with a gradient naming a vertex the mesh does not have.
void RunRogue(std::unique_ptr<ClientTransport> transport, std::atomic<bool>* stop,
              std::string* shutdown_reason, std::atomic<bool>* gone) {
  EnvelopeStamper stamper("rogue");
  wire::Envelope ready = stamper.New();
  ready.mutable_ready()->set_worker_id("rogue");
  transport->Send(Serialize(ready));
  auto last_sent = std::chrono::steady_clock::now();
  while (!stop->load()) {
    std::string payload;
    if (transport->Receive(0.02, &payload)) {
      wire::Envelope in;
      if (!in.ParseFromString(payload)) continue;
      if (in.has_shutdown()) {
        *shutdown_reason = in.shutdown().reason();
        *gone = true;
        return;
      }
      if (in.has_job()) {
        wire::Envelope out = stamper.New();
        wire::Result* result = out.mutable_result();
        result->set_job_id(in.job().job_id());
        result->set_session_id(in.job().session_id());
        wire::PairGradient* g = result->mutable_gradient();
        g->set_num_vertices(in.job().mesh().num_vertices());
        const int32_t beyond = static_cast<int32_t>(in.job().mesh().num_vertices());
        g->set_vertices(std::string(reinterpret_cast<const char*>(&beyond), 4));
        g->set_values(std::string(40, '\0'));
        transport->Send(Serialize(out));
        last_sent = std::chrono::steady_clock::now();
      }
    }
    if (std::chrono::steady_clock::now() - last_sent > std::chrono::milliseconds(40)) {
      wire::Envelope heartbeat = stamper.New();
      heartbeat.mutable_heartbeat();
      transport->Send(Serialize(heartbeat));
      last_sent = std::chrono::steady_clock::now();
    }
  }
}

TEST_F(RefineDispatch, WorkersGiveTheLocalGradientsBitForBitAndARogueIsSentAway) {
  auto network = InMemoryNetwork::Create();
  auto server = network->Bind();
  std::atomic<bool> stop{false};
  std::string rogue_reason, exit1, exit2;
  // The rogue alone gets every job until it is sent away; then the honest workers join.
  std::atomic<bool> rogue_gone{false};
  std::thread rogue(RunRogue, network->Connect(), &stop, &rogue_reason, &rogue_gone);
  std::vector<PairGradient> remote;
  std::thread w1, w2;
  std::thread starter([&] {
    for (int i = 0; i < 2000 && !rogue_gone; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    w1 = StartWorker(network, 1, &stop, &exit1);
    w2 = StartWorker(network, 2, &stop, &exit2);
  });
  {
    RefineDispatcher dispatcher(scene_, pairs_, options_, server.get(), scheduler_, WireLimits(),
                                {});
    ASSERT_TRUE(dispatcher.Compute(mesh_, kLevel, &remote));
    // A second round over the same mesh: the same again.
    std::vector<PairGradient> again;
    ASSERT_TRUE(dispatcher.Compute(mesh_, kLevel, &again));
    ExpectSame(remote, again);
    const RefineDispatchStats stats = dispatcher.stats();
    EXPECT_EQ(stats.rounds, 2);
    EXPECT_EQ(stats.jobs, 2 * static_cast<int64_t>(pairs_.size()));
  }  // the dispatcher's end: Shutdown to the workers
  starter.join();
  w1.join();
  w2.join();
  stop = true;
  rogue.join();
  ExpectSame(remote, Local());
  EXPECT_GT(remote[0].pixels, 100);
  EXPECT_EQ(rogue_reason, "its results do not fit the jobs handed out");
  EXPECT_EQ(exit1, "shutdown: refinement is over");
  EXPECT_EQ(exit2, "shutdown: refinement is over");
}

// --refine.kernel glsl travels with the jobs: a worker computes each job on a fresh thread,
// binding its GL context there, and gives what this process's GLSL kernel gives, bit for bit,
// round after round (llvmpipe here; the same code on a GPU).
TEST_F(RefineDispatch, AGlslWorkerGivesTheLocalGlslGradientsBitForBit) {
  options_.kernel = "glsl";
  auto network = InMemoryNetwork::Create();
  auto server = network->Bind();
  std::atomic<bool> stop{false};
  std::string exit_reason;
  std::thread worker = StartWorker(network, 1, &stop, &exit_reason);
  std::vector<PairGradient> first, second;
  {
    RefineDispatcher dispatcher(scene_, pairs_, options_, server.get(), scheduler_, WireLimits(),
                                {});
    ASSERT_TRUE(dispatcher.Compute(mesh_, kLevel, &first));
    ASSERT_TRUE(dispatcher.Compute(mesh_, kLevel, &second));
  }
  worker.join();
  ExpectSame(first, second);
  ExpectSame(first, Local());
  EXPECT_GT(first[0].pixels, 100);
  EXPECT_EQ(exit_reason, "shutdown: refinement is over");
}

TEST_F(RefineDispatch, AStopEndsARoundThatNoWorkerTakes) {
  auto network = InMemoryNetwork::Create();
  auto server = network->Bind();
  const auto start = std::chrono::steady_clock::now();
  RefineDispatcher dispatcher(
      scene_, pairs_, options_, server.get(), scheduler_, WireLimits(),
      [&] { return std::chrono::steady_clock::now() - start > std::chrono::milliseconds(300); });
  std::vector<PairGradient> out;
  EXPECT_FALSE(dispatcher.Compute(mesh_, kLevel, &out));
  EXPECT_TRUE(out.empty());
}

}  // namespace
}  // namespace ms
