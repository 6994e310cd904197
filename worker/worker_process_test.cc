// The worker's side of the protocol, against a scripted coordinator over the in-memory transport
// (no sockets) and a fake kernel (the real ones have their own tests).
#include "worker/worker_process.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "base/error.h"
#include "base/file_util.h"
#include "proto/content_hash.h"
#include "proto/options_codec.h"
#include "proto/wire.h"
#include "refine/refine_options.h"
#include "sweep/sweep_kernel_factory.h"
#include "testing/in_memory_network.h"
#include "worker/image_cache.h"
#include "worker/job_codec.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

// Returns one point per neighbour in front of C; throws InputError for a job without faces.
class FakeKernel : public SweepKernel {
 public:
  explicit FakeKernel(double seconds = 0) : seconds_(seconds) {}
  SweepResult Run(const SweepJob& job) override {
    if (seconds_ > 0) std::this_thread::sleep_for(std::chrono::duration<double>(seconds_));
    if (job.mesh.faces.empty())
      throw InputError("camera " + std::to_string(job.camera.id) +
                       ": no face in front of the camera");
    EXPECT_EQ(job.camera.image.cols, job.camera.view.intrinsics.width);
    SweepResult result;
    for (const SweepCamera& n : job.neighbours) {
      SweepPoint p;
      p.position = job.camera.view.Center() + Eigen::Vector3d(0, 0, 1 + n.id);
      p.ncc = 0.99f;
      p.pixel = Eigen::Vector2f(4.5f, 3.5f + n.id);
      p.cameras = {job.camera.id, n.id};
      result.points.push_back(p);
    }
    result.stats.total_s = seconds_;
    return result;
  }
  std::string Name() const override { return "fake"; }

 private:
  double seconds_;
};

class WorkerProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("worker_process_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "images");
    for (int i = 0; i < 3; ++i) {
      cv::Mat image(6, 8, CV_8U);
      cv::randu(image, 0, 255);
      const std::string path = (dir_ / "images" / ("view" + std::to_string(i) + ".png")).string();
      ASSERT_TRUE(cv::imwrite(path, image));
      paths_.push_back(path);
    }
    network_ = InMemoryNetwork::Create();
    server_ = network_->Bind();
    options_.heartbeat_interval_s = 0.05;
    options_.liveness = 5;
    options_.cache.directory = (dir_ / "cache").string();
  }
  void TearDown() override {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    fs::remove_all(dir_);
  }

  void StartWorker(double kernel_seconds = 0) {
    thread_ = std::thread([this, kernel_seconds] {
      try {
        Worker worker(
            options_,
            [this] {
              ++connections_;
              return network_->Connect();
            },
            std::make_unique<FakeKernel>(kernel_seconds));
        summary_ = worker.Run([this] { return stop_.load(); });
      } catch (const InputError& e) {
        error_ = e.what();
      }
    });
  }

  // Next envelope from the worker that is not a heartbeat (those are counted).
  bool Next(wire::Envelope* envelope, double timeout_s = 5.0) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < deadline) {
      PeerMessage message;
      if (!server_->Receive(0.01, &message)) continue;
      peer_ = message.peer;
      std::string problem;
      EXPECT_EQ(DecodeEnvelope(message.payload.data(), message.payload.size(), WireLimits{},
                               envelope, &problem),
                DecodeStatus::kOk)
          << problem;
      if (envelope->has_heartbeat()) {
        heartbeats_.push_back(envelope->heartbeat());
        continue;
      }
      return true;
    }
    return false;
  }

  void Send(wire::Envelope& envelope) { server_->Send(peer_, Serialize(envelope)); }

  wire::Job MakeJob(uint64_t id, const std::string& image_dir_override = "") {
    wire::Job job;
    job.set_job_id(id);
    job.set_iteration(1);
    job.set_session_id(77);
    for (int i = 0; i < 3; ++i) {
      View view;
      view.name = "view" + std::to_string(i);
      view.intrinsics.width = 8;
      view.intrinsics.height = 6;
      view.intrinsics.fx = view.intrinsics.fy = 10;
      view.intrinsics.cx = 4;
      view.intrinsics.cy = 3;
      view.SetCenter(Eigen::Vector3d(i, 0, -5));
      wire::JobCamera* camera = i == 0 ? job.mutable_camera() : job.add_neighbours();
      ViewToWire(i, view, camera);
      const FileHash hash = HashFile(paths_[i]);
      camera->mutable_image()->set_path(
          image_dir_override.empty() ? paths_[i]
                                     : image_dir_override + "/view" + std::to_string(i) + ".png");
      camera->mutable_image()->set_content_hash(hash.hash);
      camera->mutable_image()->set_byte_size(hash.size);
    }
    Mesh mesh;
    mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.faces = {{0, 1, 2}};
    PackMesh(mesh, job.mutable_mesh());
    OptionsToWire(SweepOptions{}, job.mutable_options());
    return job;
  }

  void SendJob(const wire::Job& job) {
    wire::Envelope envelope = stamper_.New();
    *envelope.mutable_job() = job;
    Send(envelope);
  }

  void SendShutdown() {
    wire::Envelope envelope = stamper_.New();
    envelope.mutable_shutdown()->set_reason("test over");
    Send(envelope);
  }

  fs::path dir_;
  std::vector<std::string> paths_;
  std::shared_ptr<InMemoryNetwork> network_;
  std::unique_ptr<ServerTransport> server_;
  EnvelopeStamper stamper_{"coordinator"};
  WorkerOptions options_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> connections_{0};
  WorkerSummary summary_;
  std::string error_;
  std::string peer_;
  std::vector<wire::Heartbeat> heartbeats_;
};

TEST_F(WorkerProcessTest, SaysReadyPullsAJobReturnsItsPointsAndExitsOnShutdown) {
  options_.id = "w1";
  StartWorker();
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_ready());
  EXPECT_EQ(envelope.ready().worker_id(), "w1");
  EXPECT_EQ(envelope.ready().kernel(), "fake");
  EXPECT_EQ(envelope.protocol_version(), kProtocolVersion);
  SendJob(MakeJob(42));
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_result()) << BodyName(envelope);
  const wire::Result& result = envelope.result();
  EXPECT_EQ(result.job_id(), 42u);
  EXPECT_EQ(result.session_id(), 77u);
  EXPECT_EQ(result.worker_id(), "w1");
  ASSERT_EQ(result.points_size(), 2);
  EXPECT_EQ(result.points(0).cameras(0), 0);
  EXPECT_EQ(result.points(1).cameras(1), 2);
  SendShutdown();
  thread_.join();
  EXPECT_EQ(error_, "");
  EXPECT_EQ(summary_.jobs, 1);
  EXPECT_EQ(summary_.points, 2);
  EXPECT_EQ(summary_.exit_reason, "shutdown: test over");
}

// Refinement jobs: the pair's gradient comes back instead of points; the round's mesh comes
// with the first job only, later jobs refer to it by id, and a job naming a mesh this worker
// does not hold (another id or session) is answered NEED_MESH; a pair of three cameras is a
// bad job.
TEST_F(WorkerProcessTest, RefinementJobsReturnGradientsAndAskForAMeshTheyDoNotHold) {
  StartWorker();
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  const auto refine_job = [&](uint64_t id, uint64_t session, bool with_mesh) {
    wire::Job job = MakeJob(id);
    job.set_session_id(session);
    job.mutable_neighbours()->RemoveLast();
    job.clear_options();
    job.mutable_refine()->set_mesh_id(5);
    RefineOptions options;
    options.gaussian_sigma_px = 0.5;  // a window that fits the 8 x 6 images
    OptionsToWire(options, job.mutable_refine()->mutable_options());
    // A square filling both views, so that the pair has pixels to compare.
    Mesh square;
    square.vertices = {{-4, -4, 0}, {4, -4, 0}, {4, 4, 0}, {-4, 4, 0}};
    square.faces = {{0, 1, 2}, {0, 2, 3}};
    PackMesh(square, job.mutable_mesh());
    if (!with_mesh) job.clear_mesh();
    return job;
  };
  SendJob(refine_job(1, 77, false));
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_error()) << BodyName(envelope);
  EXPECT_EQ(envelope.error().code(), wire::Error::NEED_MESH);
  SendJob(refine_job(2, 77, true));
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_result()) << BodyName(envelope);
  EXPECT_EQ(envelope.result().points_size(), 0);
  ASSERT_TRUE(envelope.result().has_gradient());
  EXPECT_EQ(envelope.result().gradient().num_vertices(), 4u);
  EXPECT_GT(envelope.result().gradient().pixels(), 0);
  const std::string first = envelope.result().gradient().SerializeAsString();
  SendJob(refine_job(3, 77, false));
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_result()) << BodyName(envelope);
  EXPECT_EQ(envelope.result().gradient().SerializeAsString(), first);
  SendJob(refine_job(4, 78, false));  // another session: not the mesh it holds
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_error());
  EXPECT_EQ(envelope.error().code(), wire::Error::NEED_MESH);
  wire::Job three = refine_job(5, 77, true);
  *three.add_neighbours() = three.neighbours(0);
  SendJob(three);
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_error());
  EXPECT_EQ(envelope.error().code(), wire::Error::BAD_JOB);
  EXPECT_NE(envelope.error().message().find("exactly one neighbour"), std::string::npos);
  SendShutdown();
  thread_.join();
  EXPECT_EQ(error_, "");
}

TEST_F(WorkerProcessTest, HeartbeatsNameTheJobWhileSweeping) {
  StartWorker(0.4);
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  SendJob(MakeJob(9));
  heartbeats_.clear();
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_result());
  int busy = 0;
  for (const wire::Heartbeat& h : heartbeats_) {
    if (h.current_job_id() == 9 && h.session_id() == 77 && h.last_job_id() == 9) ++busy;
  }
  EXPECT_GE(busy, 3);  // 0.4 s of sweeping at 0.05 s intervals
  SendShutdown();
}

TEST_F(WorkerProcessTest, AJobWhileSweepingIsRefusedAsBusyNamingTheCurrentJob) {
  StartWorker(0.4);
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  SendJob(MakeJob(9));
  SendJob(MakeJob(10));
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_error()) << BodyName(envelope);
  EXPECT_EQ(envelope.error().code(), wire::Error::BUSY);
  EXPECT_EQ(envelope.error().job_id(), 10u);
  EXPECT_EQ(envelope.error().busy_job_id(), 9u);
  EXPECT_EQ(envelope.error().busy_session_id(), 77u);
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_result()) << BodyName(envelope);
  EXPECT_EQ(envelope.result().job_id(), 9u);
  SendShutdown();
}

TEST_F(WorkerProcessTest, FetchesImagesByHashWhenThePathIsNotReadableAndCachesThem) {
  options_.limits.image_chunk_bytes = 1024;  // several pieces for a PNG of a few hundred bytes+
  StartWorker();
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  const wire::Job job = MakeJob(5, "/nonexistent/elsewhere");
  SendJob(job);
  int requests = 0;
  while (true) {
    ASSERT_TRUE(Next(&envelope));
    if (!envelope.has_image_request()) break;
    ++requests;
    const wire::ImageRequest& request = envelope.image_request();
    int index = -1;
    for (int i = 0; i < 3; ++i) {
      if (HashFile(paths_[i]).hash == request.content_hash()) index = i;
    }
    ASSERT_GE(index, 0);
    const std::string bytes = ReadFileToString(paths_[index]);
    wire::Envelope reply = stamper_.New();
    wire::ImageResponse* response = reply.mutable_image_response();
    response->set_content_hash(request.content_hash());
    response->set_offset(request.offset());
    response->set_total_size(bytes.size());
    response->set_found(true);
    EXPECT_LE(request.max_bytes(), 1024u);
    response->set_data(bytes.substr(request.offset(), 100));  // small pieces
    Send(reply);
  }
  ASSERT_TRUE(envelope.has_result()) << BodyName(envelope);
  EXPECT_GT(requests, 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(fs::exists(dir_ / "cache" / (HashHex(HashFile(paths_[i]).hash) + ".img")));
  }
  // The same job again: served from the disk cache, no request.
  SendJob(MakeJob(6, "/nonexistent/elsewhere"));
  ASSERT_TRUE(Next(&envelope));
  EXPECT_TRUE(envelope.has_result()) << BodyName(envelope);
  SendShutdown();
  thread_.join();
  EXPECT_EQ(summary_.images_fetched, 3);
}

TEST_F(WorkerProcessTest, AnImageTheCoordinatorCannotServeFailsTheJobOnThisWorker) {
  StartWorker();
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  SendJob(MakeJob(5, "/nonexistent"));
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_image_request());
  wire::Envelope reply = stamper_.New();
  reply.mutable_image_response()->set_content_hash(envelope.image_request().content_hash());
  reply.mutable_image_response()->set_error("gone");
  Send(reply);
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_error());
  EXPECT_EQ(envelope.error().code(), wire::Error::WORKER_FAILURE);
  EXPECT_EQ(envelope.error().job_id(), 5u);
  SendShutdown();
}

TEST_F(WorkerProcessTest, BadJobsAreRefusedWithoutCrashing) {
  StartWorker();
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  wire::Job bad = MakeJob(3);
  bad.mutable_mesh()->set_num_faces(1000);  // claims more faces than its bytes hold
  SendJob(bad);
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_error());
  EXPECT_EQ(envelope.error().code(), wire::Error::BAD_JOB);
  EXPECT_NE(envelope.error().message().find("mesh"), std::string::npos);
  // The kernel refuses a job (no faces): BAD_JOB with the kernel's message.
  wire::Job empty = MakeJob(4);
  PackMesh(Mesh{}, empty.mutable_mesh());
  SendJob(empty);
  ASSERT_TRUE(Next(&envelope));
  ASSERT_TRUE(envelope.has_error());
  EXPECT_EQ(envelope.error().code(), wire::Error::BAD_JOB);
  EXPECT_NE(envelope.error().message().find("no face"), std::string::npos);
  // Garbage from the coordinator is dropped; the worker still answers.
  server_->Send(peer_, "\xff\xff garbage");
  SendJob(MakeJob(8));
  ASSERT_TRUE(Next(&envelope));
  EXPECT_TRUE(envelope.has_result());
  SendShutdown();
  thread_.join();
  EXPECT_EQ(summary_.failed_jobs, 2);
}

TEST_F(WorkerProcessTest, AnotherProtocolVersionStopsTheWorkerWithAClearError) {
  StartWorker();
  wire::Envelope envelope;
  ASSERT_TRUE(Next(&envelope));
  wire::Envelope other = stamper_.New();
  other.set_protocol_version(kProtocolVersion + 1);
  other.mutable_heartbeat();
  Send(other);
  thread_.join();
  EXPECT_NE(error_.find("protocol version " + std::to_string(kProtocolVersion + 1)),
            std::string::npos)
      << error_;
}

TEST_F(WorkerProcessTest, ReconnectsWithBackOffAndGivesUpWhenNobodyAnswers) {
  options_.heartbeat_interval_s = 0.02;
  options_.liveness = 3;
  options_.reconnect_initial_s = 0.01;
  options_.reconnect_max_s = 0.04;
  options_.give_up_after_s = 0.6;
  const auto start = std::chrono::steady_clock::now();
  StartWorker();
  thread_.join();
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_NE(error_.find("giving up"), std::string::npos) << error_;
  EXPECT_GE(elapsed, 0.6);
  EXPECT_LT(elapsed, 3.0);
  EXPECT_GE(connections_.load(), 4);  // the first connection and several reconnections
}

TEST(ImageCache, UsesLocalFilesOnlyWhenSizeAndHashMatch) {
  const fs::path dir = fs::path(::testing::TempDir()) / "image_cache_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  cv::Mat image(6, 8, CV_8U, cv::Scalar(100));
  const std::string path = (dir / "a.png").string();
  ASSERT_TRUE(cv::imwrite(path, image));
  const FileHash hash = HashFile(path);
  ImageCacheOptions options;
  options.directory = (dir / "cache").string();
  ImageCache cache(options);
  EXPECT_EQ(cache.Locate(ImageRef{path, hash.hash, hash.size}), path);
  EXPECT_EQ(cache.Locate(ImageRef{path, hash.hash ^ 1, hash.size}), "");  // other content
  EXPECT_EQ(cache.Locate(ImageRef{path + ".x", hash.hash, hash.size}), "");
  const std::string bytes = ReadFileToString(path);
  EXPECT_THROW(cache.Store(ImageRef{"x", hash.hash ^ 1, hash.size}, bytes), InputError);
  const std::string stored = cache.Store(ImageRef{"x", hash.hash, hash.size}, bytes);
  EXPECT_EQ(cache.Locate(ImageRef{"/elsewhere/a.png", hash.hash, hash.size}), stored);
  View view;
  view.intrinsics.width = 8;
  view.intrinsics.height = 6;
  view.intrinsics.fx = view.intrinsics.fy = 10;
  const SweepCamera a = cache.Load(1, view, hash.hash, stored);
  const SweepCamera b = cache.Load(2, view, hash.hash, stored);
  EXPECT_EQ(b.id, 2);
  EXPECT_NEAR(a.image.at<float>(2, 3), 100 / 255.0, 1e-6);
  EXPECT_EQ(cache.stats().decoded, 1);
  EXPECT_EQ(cache.stats().memory_hits, 1);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ms
