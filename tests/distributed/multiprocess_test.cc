// The distributed run with real processes and real sockets on loopback: `manisweep coordinator`
// and `manisweep worker` processes (and `manisweep reconstruct`), on a small synthetic pyramid.
// The final mesh must be a closed 2-manifold and byte-identical whatever the number of workers,
// a worker killed in the middle of a job, or a coordinator killed and resumed.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "base/file_util.h"
#include "coordinator/run_store.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "proto/wire.h"
#include "proto/zmq_transport.h"
#include "tests/distributed/child_process.h"
#include "tests/distributed/pyramid_scene_files.h"

namespace ms {
namespace {

namespace fs = std::filesystem;
using test::ChildProcess;

const char* const kBinary = MS_BINARY;
// Short heartbeats so deaths are noticed within a second (a loaded machine does not fake one),
// and sweep options scaled to the 160 x 120 images.
const char* const kRunOptions =
    "--heartbeat-interval 0.1 --liveness 8 --sweep.tile-size-px 10 --sweep.gaussian-sigma-px 4";

// Splits on spaces (the test's paths have none).
std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> words;
  std::istringstream in(text);
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

class MultiProcessTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::path(::testing::TempDir()) /
                         ("manisweep_multiprocess_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    testing::PyramidSceneFileOptions options;
    options.width = 160;
    options.height = 120;
    scene_ = new std::string(testing::WritePyramidSceneFiles((*root_ / "scene").string(), options));
  }
  static void TearDownTestSuite() {
    // Kept for inspection after a failure, or with MS_KEEP_TEST_OUTPUT set.
    if (!HasFailure() && !std::getenv("MS_KEEP_TEST_OUTPUT")) fs::remove_all(*root_);
    delete root_;
    delete scene_;
  }

  static std::string Dir(const std::string& name) {
    const fs::path dir = *root_ / name;
    fs::create_directories(dir);
    return dir.string();
  }

  static std::vector<std::string> CoordinatorArgs(const std::string& out, int port,
                                                  int iterations = 3) {
    return Split("coordinator --input " + *scene_ +
                 " --bind tcp://127.0.0.1:" + std::to_string(port) + " --output " + out +
                 " --max-iterations " + std::to_string(iterations) + " " + kRunOptions +
                 " --lease 60 --progress-interval 1");
  }
  static std::vector<std::string> WorkerArgs(int port, const std::string& id) {
    return Split("--log-level info worker --connect tcp://127.0.0.1:" + std::to_string(port) +
                 " --id " + id +
                 " --threads 1 --heartbeat-interval 0.1 --liveness 8 --reconnect-initial 0.1"
                 " --reconnect-max 0.5 --give-up-after 30 --cache-dir " +
                 (*root_ / "cache" / id).string());
  }

  // A complete run: a coordinator and `workers` worker processes. Returns the output dir.
  static std::string Run(const std::string& name, int workers) {
    const std::string out = Dir(name);
    const int port = test::FreePort();
    ChildProcess coordinator(kBinary, CoordinatorArgs(out, port), out + "/coordinator.log");
    std::vector<std::unique_ptr<ChildProcess>> pool;
    for (int i = 0; i < workers; ++i) {
      const std::string id = "w" + std::to_string(i + 1);
      pool.push_back(
          std::make_unique<ChildProcess>(kBinary, WorkerArgs(port, id), out + "/" + id + ".log"));
    }
    EXPECT_TRUE(coordinator.Wait(90)) << coordinator.Log();
    EXPECT_EQ(coordinator.exit_code(), 0) << coordinator.Log();
    for (auto& worker : pool) {
      EXPECT_TRUE(worker->Wait(10)) << worker->Log();
      EXPECT_EQ(worker->exit_code(), 0) << worker->Log();
    }
    return out;
  }

  // The 2-worker run every comparison is against (made once).
  static const std::string& Reference() {
    static const std::string out = Run("reference_2_workers", 2);
    return out;
  }

  static std::string FinalMesh(const std::string& out) {
    return ReadFileToString(out + "/final.ply");
  }

  static fs::path* root_;
  static std::string* scene_;
};

fs::path* MultiProcessTest::root_ = nullptr;
std::string* MultiProcessTest::scene_ = nullptr;

TEST_F(MultiProcessTest, TwoWorkersGiveAClosedManifoldAndTheOutputs) {
  const std::string out = Reference();
  const Mesh initial = ReadMesh(out + "/initial.ply");
  const Mesh final_mesh = ReadMesh(out + "/final.ply");
  const MeshReport report = CheckMesh(final_mesh);  // self-intersections included
  EXPECT_TRUE(report.is_closed_manifold) << report.ToTable(out + "/final.ply");
  EXPECT_GT(final_mesh.NumVertices(), initial.NumVertices() + 50);

  const RunRecord record = ReadRunFile(out + "/run.h5");
  EXPECT_EQ(record.completed_iterations(), 3);
  ASSERT_EQ(record.iterations.size(), 4u);
  int64_t jobs = 0, worker_jobs = 0;
  std::set<std::string> workers;
  for (const IterationStats& s : record.iterations) {
    jobs += s.jobs;
    EXPECT_EQ(
        s.points_inserted + s.discarded_conflict + s.discarded_duplicate + s.discarded_outside,
        s.points_found)
        << "iteration " << s.iteration;
  }
  for (const WorkerIterationStats& w : record.workers) {
    worker_jobs += w.jobs;
    workers.insert(w.worker);
  }
  EXPECT_EQ(jobs, 9);  // 3 cameras x 3 iterations
  EXPECT_EQ(worker_jobs, jobs);
  EXPECT_EQ(workers, (std::set<std::string>{"w1", "w2"}));
  EXPECT_EQ(record.iterations.back().vertices, static_cast<int64_t>(final_mesh.NumVertices()));

  const auto summary = nlohmann::json::parse(ReadFileToString(out + "/summary.json"));
  EXPECT_EQ(summary["status"], "finished");
  EXPECT_EQ(summary["final_mesh"]["closed_manifold"], true);
  EXPECT_EQ(summary["iterations_completed"], 3);
  for (const auto& row : summary["iterations"]) {
    std::printf(
        "iteration %d: %d jobs, %d points found, %d inserted, %d vertices; sweep %.2f s, "
        "insert %.3f s\n",
        row["iteration"].get<int>(), row["jobs"].get<int>(), row["points_found"].get<int>(),
        row["points_inserted"].get<int>(), row["vertices"].get<int>(),
        row["seconds_sweep"].get<double>(), row["seconds_insert"].get<double>());
  }
}

TEST_F(MultiProcessTest, OneTwoAndThreeWorkersGiveTheIdenticalMesh) {
  const std::string reference = FinalMesh(Reference());
  EXPECT_EQ(FinalMesh(Run("one_worker", 1)), reference);
  EXPECT_EQ(FinalMesh(Run("three_workers", 3)), reference);
}

TEST_F(MultiProcessTest, AWorkerKilledInTheMiddleOfAJobChangesNothing) {
  const std::string reference = FinalMesh(Reference());
  const std::string out = Dir("killed_worker");
  const int port = test::FreePort();
  ChildProcess coordinator(kBinary, CoordinatorArgs(out, port), out + "/coordinator.log");
  std::vector<std::string> slow = WorkerArgs(port, "victim");
  slow.insert(slow.end(), {"--debug.delay-s", "2"});
  ChildProcess victim(kBinary, slow, out + "/victim.log");
  ASSERT_TRUE(coordinator.WaitForLog("worker victim joined", 30)) << coordinator.Log();
  ChildProcess survivor(kBinary, WorkerArgs(port, "survivor"), out + "/survivor.log");
  ASSERT_TRUE(victim.WaitForLog(" started: ", 30)) << victim.Log();
  victim.Signal(SIGKILL);  // in its 2 s pause before the sweep: mid-job
  ASSERT_TRUE(victim.Wait(5));
  EXPECT_EQ(victim.term_signal(), SIGKILL);
  ASSERT_TRUE(coordinator.Wait(90)) << coordinator.Log();
  EXPECT_EQ(coordinator.exit_code(), 0) << coordinator.Log();
  EXPECT_TRUE(survivor.Wait(10));
  const std::string log = coordinator.Log();
  EXPECT_NE(log.find("worker victim went silent"), std::string::npos) << log;
  EXPECT_NE(log.find("goes back to the queue"), std::string::npos) << log;
  EXPECT_EQ(FinalMesh(out), reference);
}

TEST_F(MultiProcessTest, AKilledCoordinatorResumesToTheIdenticalMesh) {
  const std::string reference = FinalMesh(Reference());
  const std::string out = Dir("killed_coordinator");
  const int port = test::FreePort();
  std::vector<std::unique_ptr<ChildProcess>> pool;
  {
    ChildProcess first(kBinary, CoordinatorArgs(out, port), out + "/coordinator1.log");
    for (const char* id : {"w1", "w2"}) {
      pool.push_back(
          std::make_unique<ChildProcess>(kBinary, WorkerArgs(port, id), out + "/" + id + ".log"));
    }
    ASSERT_TRUE(first.WaitForLog("checkpoint of iteration 1 written", 60)) << first.Log();
    first.Signal(SIGKILL);
    ASSERT_TRUE(first.Wait(5));
    EXPECT_EQ(first.term_signal(), SIGKILL);
  }
  const RunRecord checkpoint = ReadRunFile(out + "/run.h5");
  EXPECT_GE(checkpoint.completed_iterations(), 1);
  EXPECT_FALSE(fs::exists(out + "/final.ply"));
  // Longer than the workers' liveness: they go through reconnection with back-off.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  std::vector<std::string> args = CoordinatorArgs(out, port);
  args.push_back("--resume");
  ChildProcess second(kBinary, args, out + "/coordinator2.log");
  // On a failure, the workers' side of it too (their logs go with the test's directory).
  const auto logs = [&] {
    std::string all = second.Log();
    for (auto& worker : pool) all += "\n--- worker ---\n" + worker->Log();
    return all;
  };
  ASSERT_TRUE(second.Wait(90)) << logs();
  EXPECT_EQ(second.exit_code(), 0) << logs();
  EXPECT_NE(second.Log().find("replayed iteration 1"), std::string::npos) << second.Log();
  for (auto& worker : pool) {
    EXPECT_TRUE(worker->Wait(10)) << worker->Log();
    EXPECT_EQ(worker->exit_code(), 0) << worker->Log();
    EXPECT_NE(worker->Log().find("reconnecting in"), std::string::npos) << worker->Log();
  }
  EXPECT_EQ(FinalMesh(out), reference);
  // A finished run resumed again only rewrites the same final mesh.
  ChildProcess third(kBinary, args, out + "/coordinator3.log");
  ASSERT_TRUE(third.Wait(30)) << third.Log();
  EXPECT_EQ(third.exit_code(), 0) << third.Log();
  EXPECT_EQ(FinalMesh(out), reference);
  // Without --resume, an existing run is never overwritten.
  ChildProcess fourth(kBinary, CoordinatorArgs(out, port), out + "/coordinator4.log");
  ASSERT_TRUE(fourth.Wait(30));
  EXPECT_EQ(fourth.exit_code(), 2);
  EXPECT_NE(fourth.Log().find("pass --resume"), std::string::npos) << fourth.Log();
}

TEST_F(MultiProcessTest, ReconstructStopsEverythingOnCtrlCAndResumesToTheIdenticalMesh) {
  const std::string reference = FinalMesh(Reference());
  const std::string out = Dir("reconstruct");
  std::vector<std::string> args =
      Split("reconstruct --input " + *scene_ + " --output " + out +
            " --workers 2 --max-iterations 3 --no-refine " + kRunOptions);
  std::vector<pid_t> children;
  {
    ChildProcess run(kBinary, args, out + "/reconstruct1.log");
    ASSERT_TRUE(run.WaitForLog("iteration 1 done", 60)) << run.Log();
    std::ifstream list("/proc/" + std::to_string(run.pid()) + "/task/" + std::to_string(run.pid()) +
                       "/children");
    for (pid_t pid; list >> pid;) children.push_back(pid);
    EXPECT_EQ(children.size(), 2u);
    run.Signal(SIGINT);
    ASSERT_TRUE(run.Wait(30)) << run.Log();
    EXPECT_EQ(run.exit_code(), 130) << run.Log();
  }
  for (pid_t pid : children) {
    bool gone = false;
    for (int i = 0; i < 500 && !gone; ++i) {
      gone = ::kill(pid, 0) != 0;
      if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_TRUE(gone) << "worker process " << pid << " outlived reconstruct";
  }
  args.push_back("--resume");
  ChildProcess resumed(kBinary, args, out + "/reconstruct2.log");
  ASSERT_TRUE(resumed.Wait(90)) << resumed.Log();
  EXPECT_EQ(resumed.exit_code(), 0) << resumed.Log();
  EXPECT_EQ(FinalMesh(out), reference);
}

TEST_F(MultiProcessTest, AWorkerWithTheWrongCurveKeyIsRefused) {
  if (!CurveAvailable()) GTEST_SKIP() << "this libzmq has no CURVE";
  const std::string out = Dir("curve");
  const std::string keys = Dir("curve/keys");
  fs::create_directories(keys + "/allowed");
  for (const char* name : {"server", "good", "bad"}) {
    ChildProcess keygen(kBinary, {"keygen", "--output", keys + "/" + name}, out + "/keygen.log");
    ASSERT_TRUE(keygen.Wait(10));
    ASSERT_EQ(keygen.exit_code(), 0) << keygen.Log();
  }
  fs::copy_file(keys + "/good.key", keys + "/allowed/good.key");
  const int port = test::FreePort();
  std::vector<std::string> args = CoordinatorArgs(out, port, 1);
  args.insert(args.end(), {"--curve-secret-key", keys + "/server.key_secret", "--curve-public-keys",
                           keys + "/allowed"});
  ChildProcess coordinator(kBinary, args, out + "/coordinator.log");
  std::vector<std::string> bad_args = WorkerArgs(port, "intruder");
  bad_args.insert(bad_args.end(), {"--curve-server-key", keys + "/server.key", "--curve-secret-key",
                                   keys + "/bad.key_secret"});
  ChildProcess intruder(kBinary, bad_args, out + "/intruder.log");
  ASSERT_TRUE(intruder.Wait(20)) << intruder.Log();
  EXPECT_EQ(intruder.exit_code(), 2) << intruder.Log();
  EXPECT_NE(intruder.Log().find("refused this worker's CURVE key"), std::string::npos)
      << intruder.Log();
  std::vector<std::string> good_args = WorkerArgs(port, "friend");
  good_args.insert(good_args.end(), {"--curve-server-key", keys + "/server.key",
                                     "--curve-secret-key", keys + "/good.key_secret"});
  ChildProcess worker(kBinary, good_args, out + "/friend.log");
  ASSERT_TRUE(coordinator.Wait(60)) << coordinator.Log();
  EXPECT_EQ(coordinator.exit_code(), 0) << coordinator.Log();
  EXPECT_TRUE(worker.Wait(10));
  EXPECT_EQ(worker.exit_code(), 0) << worker.Log();
  const std::string log = coordinator.Log();
  EXPECT_NE(log.find("refused a worker from 127.0.0.1: its public key"), std::string::npos) << log;
  EXPECT_NE(log.find("worker friend joined"), std::string::npos) << log;
  EXPECT_EQ(log.find("worker intruder joined"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(out + "/final.ply"));
}

// Beyond loopback a coordinator needs CURVE keys or an explicit --insecure.
TEST_F(MultiProcessTest, ANetworkBindWithoutCurveNeedsInsecure) {
  const std::string out = Dir("insecure");
  // No iteration: a run that needs no worker ends after the initial manifold.
  std::vector<std::string> args = CoordinatorArgs(out, test::FreePort(), 0);
  for (size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] == "--bind") args[i + 1] = "tcp://*:" + std::to_string(test::FreePort());
  }
  ChildProcess refused(kBinary, args, out + "/refused.log");
  ASSERT_TRUE(refused.Wait(20)) << refused.Log();
  EXPECT_EQ(refused.exit_code(), 2) << refused.Log();
  EXPECT_NE(refused.Log().find("without CURVE"), std::string::npos) << refused.Log();
  EXPECT_FALSE(fs::exists(out + "/run.h5"));  // refused before anything was written
  args.push_back("--insecure");
  ChildProcess insecure(kBinary, args, out + "/insecure.log");
  ASSERT_TRUE(insecure.Wait(60)) << insecure.Log();
  EXPECT_EQ(insecure.exit_code(), 0) << insecure.Log();
  EXPECT_NE(insecure.Log().find("accepts unauthenticated"), std::string::npos) << insecure.Log();
}

// A raw ZeroMQ client sends junk and a foreign protocol version; the coordinator logs each,
// answers the version mismatch, and finishes the run with a real worker.
TEST_F(MultiProcessTest, BadMessagesAreLoggedAndDroppedAndAnotherVersionIsRefused) {
  const std::string out = Dir("protocol");
  const int port = test::FreePort();
  std::vector<std::string> args = CoordinatorArgs(out, port, 1);
  args.insert(args.end(), {"--max-message-mb", "0.0625"});  // 64 KiB
  ChildProcess coordinator(kBinary, args, out + "/coordinator.log");
  ASSERT_TRUE(coordinator.WaitForLog("coordinator listening", 30)) << coordinator.Log();

  zmq::context_t context;
  zmq::socket_t raw(context, zmq::socket_type::dealer);
  raw.set(zmq::sockopt::linger, 0);
  raw.connect("tcp://127.0.0.1:" + std::to_string(port));
  raw.send(zmq::str_buffer("\xff\xff\xff\xff not an envelope"), zmq::send_flags::none);
  raw.send(zmq::buffer(std::string(100000, 'x')), zmq::send_flags::none);  // over 64 KiB
  raw.send(zmq::str_buffer("part one"), zmq::send_flags::sndmore);
  raw.send(zmq::str_buffer("part two"), zmq::send_flags::none);
  wire::Envelope future;
  future.set_protocol_version(kProtocolVersion + 1);
  future.set_sender("time-traveller");
  future.mutable_ready()->set_worker_id("time-traveller");
  raw.send(zmq::buffer(Serialize(future)), zmq::send_flags::none);
  bool refused = false;
  for (int i = 0; i < 100 && !refused; ++i) {
    zmq::message_t reply;
    if (!raw.recv(reply, zmq::recv_flags::dontwait)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      continue;
    }
    wire::Envelope envelope;
    std::string problem;
    if (DecodeEnvelope(reply.data(), reply.size(), WireLimits{}, &envelope, &problem) ==
            DecodeStatus::kOk &&
        envelope.has_error()) {
      EXPECT_EQ(envelope.error().code(), wire::Error::VERSION_MISMATCH);
      refused = true;
    }
  }
  EXPECT_TRUE(refused);
  ChildProcess worker(kBinary, WorkerArgs(port, "honest"), out + "/honest.log");
  ASSERT_TRUE(coordinator.Wait(60)) << coordinator.Log();
  EXPECT_EQ(coordinator.exit_code(), 0) << coordinator.Log();
  const std::string log = coordinator.Log();
  EXPECT_NE(log.find("(malformed): "), std::string::npos) << log;
  EXPECT_NE(log.find("(oversized): 100000 bytes, over the limit of 65536"), std::string::npos)
      << log;
  EXPECT_NE(log.find("dropped a message of 2 frames"), std::string::npos) << log;
  EXPECT_NE(log.find("refused worker time-traveller: it speaks protocol version " +
                     std::to_string(kProtocolVersion + 1)),
            std::string::npos)
      << log;
  EXPECT_TRUE(fs::exists(out + "/final.ply"));
}

}  // namespace
}  // namespace ms
