#include "proto/wire.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "base/error.h"

namespace ms {
namespace {

TEST(Wire, EnvelopeRoundTrip) {
  EnvelopeStamper stamper("worker-a");
  wire::Envelope out = stamper.New();
  out.mutable_heartbeat()->set_current_job_id(42);
  const std::string bytes = Serialize(out);
  wire::Envelope in;
  std::string problem;
  ASSERT_EQ(DecodeEnvelope(bytes.data(), bytes.size(), WireLimits{}, &in, &problem),
            DecodeStatus::kOk);
  EXPECT_EQ(in.sender(), "worker-a");
  EXPECT_EQ(in.message_id(), 1u);
  EXPECT_EQ(in.protocol_version(), kProtocolVersion);
  EXPECT_EQ(in.heartbeat().current_job_id(), 42u);
  EXPECT_STREQ(BodyName(in), "heartbeat");
  EXPECT_EQ(stamper.New().message_id(), 2u);
}

TEST(Wire, WrongVersionIsReportedWithBothVersions) {
  wire::Envelope out;
  out.set_protocol_version(kProtocolVersion + 1);
  out.mutable_ready()->set_worker_id("w");
  const std::string bytes = Serialize(out);
  wire::Envelope in;
  std::string problem;
  EXPECT_EQ(DecodeEnvelope(bytes.data(), bytes.size(), WireLimits{}, &in, &problem),
            DecodeStatus::kWrongVersion);
  EXPECT_NE(problem.find("protocol version " + std::to_string(kProtocolVersion + 1)),
            std::string::npos);
  EXPECT_NE(problem.find("speaks version " + std::to_string(kProtocolVersion)), std::string::npos);
}

TEST(Wire, MalformedOversizedAndEmptyEnvelopesAreRefused) {
  wire::Envelope in;
  std::string problem;
  const std::string garbage = "\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\x01 not protobuf";
  EXPECT_EQ(DecodeEnvelope(garbage.data(), garbage.size(), WireLimits{}, &in, &problem),
            DecodeStatus::kMalformed);
  // Truncated valid message.
  EnvelopeStamper stamper("w");
  wire::Envelope out = stamper.New();
  out.mutable_ready()->set_worker_id(std::string(100, 'x'));
  const std::string bytes = Serialize(out);
  EXPECT_EQ(DecodeEnvelope(bytes.data(), bytes.size() - 10, WireLimits{}, &in, &problem),
            DecodeStatus::kMalformed);
  // Oversized: refused before parsing.
  WireLimits small;
  small.max_message_bytes = 64;
  EXPECT_EQ(DecodeEnvelope(bytes.data(), bytes.size(), small, &in, &problem),
            DecodeStatus::kOversized);
  EXPECT_NE(problem.find("over the limit of 64"), std::string::npos);
  // An envelope with the right version but no body (e.g. an empty frame: version 0).
  wire::Envelope empty = stamper.New();
  const std::string empty_bytes = Serialize(empty);
  EXPECT_EQ(DecodeEnvelope(empty_bytes.data(), empty_bytes.size(), WireLimits{}, &in, &problem),
            DecodeStatus::kNoBody);
  EXPECT_EQ(DecodeEnvelope("", 0, WireLimits{}, &in, &problem), DecodeStatus::kWrongVersion);
}

TEST(Wire, LimitsAreChecked) {
  WireLimits limits;
  EXPECT_NO_THROW(limits.Check());
  limits.max_message_bytes = 1000;
  EXPECT_THROW(limits.Check(), InputError);
  limits = WireLimits{};
  limits.image_chunk_bytes = limits.max_message_bytes;
  EXPECT_THROW(limits.Check(), InputError);
}

TEST(Wire, MeshRoundTripIsExact) {
  Mesh mesh;
  mesh.vertices = {{0.1, -2.5e-17, 3}, {1.0 / 3, 2, 1e300}, {-0.0, 5, 6}};
  mesh.faces = {{0, 1, 2}, {2, 1, 0}};
  wire::PackedMesh packed;
  PackMesh(mesh, &packed);
  EXPECT_EQ(packed.vertices().size(), 72u);
  EXPECT_EQ(packed.faces().size(), 24u);
  const Mesh back = UnpackMesh(packed, "job 1");
  EXPECT_EQ(back.vertices, mesh.vertices);
  EXPECT_EQ(back.faces, mesh.faces);
  // Little-endian on the wire: the first byte of vertex 0's x is the lowest byte of 0.1.
  EXPECT_EQ(static_cast<unsigned char>(packed.vertices()[0]), 0x9a);
}

TEST(Wire, BadMeshesThrowNamingTheProblem) {
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  wire::PackedMesh packed;
  PackMesh(mesh, &packed);
  wire::PackedMesh bad = packed;
  bad.set_num_vertices(1000000000);  // claims far more than the bytes hold
  EXPECT_THROW(UnpackMesh(bad, "job"), InputError);
  bad = packed;
  bad.set_num_vertices(2);  // face 0 refers to vertex 2
  bad.mutable_vertices()->resize(48);
  try {
    UnpackMesh(bad, "job 7");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("job 7: mesh: face 0 refers to vertex 2"),
              std::string::npos)
        << e.what();
  }
  Mesh nan = mesh;
  nan.vertices[1].x() = std::numeric_limits<double>::quiet_NaN();
  PackMesh(nan, &bad);
  EXPECT_THROW(UnpackMesh(bad, "job"), InputError);
}

TEST(Wire, ViewRoundTripAndValidation) {
  View view;
  view.name = "0003.png";
  view.intrinsics.width = 640;
  view.intrinsics.height = 480;
  view.intrinsics.fx = 500.25;
  view.intrinsics.fy = 501;
  view.intrinsics.cx = 320.5;
  view.intrinsics.cy = 239.75;
  view.intrinsics.k1 = -0.1;
  view.intrinsics.p2 = 1e-4;
  view.R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  view.t = Eigen::Vector3d(0.1, -0.2, 3);
  wire::JobCamera camera;
  ViewToWire(3, view, &camera);
  const View back = ViewFromWire(camera, "job");
  EXPECT_EQ(camera.id(), 3);
  EXPECT_EQ(back.name, view.name);
  EXPECT_TRUE(back.intrinsics == view.intrinsics);
  EXPECT_EQ(back.R, view.R);
  EXPECT_EQ(back.t, view.t);

  wire::JobCamera bad = camera;
  bad.mutable_rotation()->RemoveLast();
  EXPECT_THROW(ViewFromWire(bad, "job"), InputError);
  bad = camera;
  bad.set_rotation(0, 5.0);
  EXPECT_THROW(ViewFromWire(bad, "job"), InputError);
  bad = camera;
  bad.mutable_intrinsics()->set_fx(std::numeric_limits<double>::infinity());
  EXPECT_THROW(ViewFromWire(bad, "job"), InputError);
  bad = camera;
  bad.mutable_intrinsics()->set_width(0);
  EXPECT_THROW(ViewFromWire(bad, "job"), InputError);
}

TEST(Wire, JobIds) {
  const uint64_t id = MakeJobId(12, 345);
  EXPECT_EQ(JobIdIteration(id), 12u);
  EXPECT_EQ(JobIdCamera(id), 345u);
  EXPECT_NE(MakeJobId(1, 0), MakeJobId(0, 1));
}

}  // namespace
}  // namespace ms
