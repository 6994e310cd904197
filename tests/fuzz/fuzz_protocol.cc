// libFuzzer targets for the protocol: arbitrary frames decoded and handled as the coordinator
// (FUZZ_COORDINATOR: a Result checked against a fixed job, the check every worker's result
// passes before its points are used) or a worker (a Job turned into the sweep job's cameras,
// mesh and options, as Worker does before fetching images) handles them. Anything may throw
// InputError; nothing may crash, leak or hang. With MS_WRITE_SEEDS=DIR set, the target first
// writes valid frames there (the seed corpus of tests/fuzz/run_fuzzers.sh).
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "base/error.h"
#include "coordinator/insertion_batch.h"
#include "fuzz_util.h"
#include "proto/wire.h"
#include "sweep/sweep_options.h"
#include "testing/test_job.h"

namespace ms::fuzz {
namespace {

std::vector<std::string> Seeds() {
  EnvelopeStamper stamper("seed");
  std::vector<std::string> seeds;
  wire::Envelope job = stamper.New();
  *job.mutable_job() = testing::MakeSmallTestJob();
  seeds.push_back(Serialize(job));
  wire::Envelope result = stamper.New();
  result.mutable_result()->set_job_id(uint64_t{1} << 32 | 2);
  for (double x : {-0.5, 0.0, 0.7}) {
    wire::SweepPoint* p = result.mutable_result()->add_points();
    p->set_x(x);
    p->set_y(0.25);
    p->set_z(5.1);
    p->set_pixel_x(static_cast<float>(500 * x / 5.1 + 320));
    p->set_pixel_y(static_cast<float>(500 * 0.25 / 5.1 + 240));
    p->add_cameras(2);
    p->add_cameras(3);
  }
  seeds.push_back(Serialize(result));
  wire::Envelope heartbeat = stamper.New();
  heartbeat.mutable_heartbeat()->set_current_job_id(7);
  seeds.push_back(Serialize(heartbeat));
  return seeds;
}

}  // namespace
}  // namespace ms::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("MS_WRITE_SEEDS")) {
    std::filesystem::create_directories(dir);
    int i = 0;
    for (const std::string& seed : ms::fuzz::Seeds()) {
      std::ofstream(std::string(dir) + "/seed" + std::to_string(i++), std::ios::binary) << seed;
    }
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ms;
  (void)fuzz::kQuiet;
  wire::Envelope envelope;
  std::string problem;
  if (DecodeEnvelope(data, size, WireLimits(), &envelope, &problem) != DecodeStatus::kOk) return 0;
  try {
#if FUZZ_COORDINATOR
    static const JobBounds bounds = JobBoundsFromWire(testing::MakeSmallTestJob());
    if (envelope.has_result()) {
      std::vector<FoundPoint> points;
      ValidateResultPoints(envelope.result(), bounds, &points);
    }
#else
    if (envelope.has_job()) {
      const wire::Job& job = envelope.job();
      ViewFromWire(job.camera(), "job");
      for (const wire::JobCamera& n : job.neighbours()) ViewFromWire(n, "job");
      UnpackMesh(job.mesh(), "job");
      OptionsFromWire<SweepOptions>(job.options()).Check();
    }
#endif
  } catch (const InputError&) {
  }
  return 0;
}
