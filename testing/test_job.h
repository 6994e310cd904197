// Test-only, header-only: a small job as the coordinator hands them out, for the result check's
// tests (insertion_batch_test.cc) and the protocol fuzzer (tests/fuzz/fuzz_protocol.cc).
// Camera 2 at the origin looking along +z (640 x 480, f = 500) with neighbours 0 and 3 a unit
// apart; its visible mesh a square at z = 5; default sweep options (19 offsets, automatic alpha,
// so points may lie at camera z within 5 -+ 9 x 0.02 x 5).
#pragma once

#include <cstdint>

#include "mesh/mesh.h"
#include "proto/manisweep.pb.h"
#include "proto/options_codec.h"
#include "proto/wire.h"
#include "scene/camera.h"
#include "sweep/sweep_options.h"

namespace ms::testing {

inline wire::Job MakeSmallTestJob() {
  wire::Job job;
  job.set_job_id(uint64_t{1} << 32 | 2);
  job.set_iteration(1);
  View view;
  view.intrinsics.width = 640;
  view.intrinsics.height = 480;
  view.intrinsics.fx = view.intrinsics.fy = 500;
  view.intrinsics.cx = 320;
  view.intrinsics.cy = 240;
  ViewToWire(2, view, job.mutable_camera());
  for (int32_t n : {0, 3}) {
    View other = view;
    other.SetCenter({n - 1.0, 0, 0});
    ViewToWire(n, other, job.add_neighbours());
  }
  Mesh square;
  square.vertices = {{-2, -2, 5}, {2, -2, 5}, {2, 2, 5}, {-2, 2, 5}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  PackMesh(square, job.mutable_mesh());
  OptionsToWire(SweepOptions(), job.mutable_options());
  return job;
}

}  // namespace ms::testing
