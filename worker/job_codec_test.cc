// The sweep and refine options travel field by field: the structs (sweep/sweep_options_def.h,
// refine/refine_options_def.h) and the wire messages (proto/manisweep.proto) must agree, and a
// job's options arrive as they were sent.
#include <gtest/gtest.h>

#include "base/error.h"
#include "proto/manisweep.pb.h"
#include "proto/options_codec.h"
#include "refine/refine_options.h"
#include "sweep/sweep_options.h"

namespace ms {
namespace {

TEST(JobCodec, SweepOptionsAndTheirWireMessageAgreeFieldByField) {
  const std::vector<std::string> problems =
      OptionGroupMismatches<SweepOptions>(wire::SweepOptions());
  EXPECT_TRUE(problems.empty()) << problems.front();
}

TEST(JobCodec, RefineOptionsAndTheirWireMessageAgreeFieldByField) {
  const std::vector<std::string> problems =
      OptionGroupMismatches<RefineOptions>(wire::RefineOptions());
  EXPECT_TRUE(problems.empty()) << problems.front();
  RefineOptions sent;
  sent.iterations = 7;
  sent.max_edge_px = 6.5;
  sent.max_vertices = int64_t{1} << 40;
  wire::RefineOptions message;
  OptionsToWire(sent, &message);
  EXPECT_EQ(OptionGroupText(OptionsFromWire<RefineOptions>(message)), OptionGroupText(sent));
}

TEST(JobCodec, AMessageOfAnotherGroupIsReportedAsDisagreeing) {
  // The check itself can fail.
  const std::vector<std::string> problems = OptionGroupMismatches<SweepOptions>(wire::Intrinsics());
  ASSERT_FALSE(problems.empty());
  EXPECT_EQ(problems.front(), "ms.wire.Intrinsics has no field num_offsets");
  EXPECT_EQ(problems.back(), "ms.wire.Intrinsics.k3 is no option of the group");
}

TEST(JobCodec, SweepOptionsRoundTripThroughTheWire) {
  SweepOptions sent;
  sent.num_offsets = 7;
  sent.alpha = 0.25;
  sent.alpha_parallax_px = 1.5;
  sent.ncc_threshold = 0.9;
  sent.gaussian_sigma_px = 3;
  sent.tile_size_px = 17;
  sent.tiles_across = 9;
  sent.min_matching_neighbours = 3;
  sent.support_ncc = 0.7;
  sent.strict_support = true;
  sent.winners_must_move = true;
  sent.image_noise_target = 1.5;
  sent.min_texture_variance = 2e-4;
  sent.min_window_weight = 0.75;
  sent.occlusion_tolerance = 0.02;
  sent.max_image_dimension = 800;
  sent.pyramid_level = 2;
  wire::SweepOptions message;
  OptionsToWire(sent, &message);
  EXPECT_EQ(message.num_offsets(), 7);
  EXPECT_EQ(message.pyramid_level(), 2);
  const SweepOptions received = OptionsFromWire<SweepOptions>(message);
  EXPECT_EQ(OptionGroupText(received), OptionGroupText(sent));
}

TEST(JobCodec, AnOptionThisBuildDoesNotKnowIsRefused) {
  wire::SweepOptions message;
  OptionsToWire(SweepOptions{}, &message);
  // What a newer coordinator's extra option looks like to this build.
  message.GetReflection()->MutableUnknownFields(&message)->AddVarint(901, 1);
  wire::SweepOptions received;
  ASSERT_TRUE(received.ParseFromString(message.SerializeAsString()));
  try {
    OptionsFromWire<SweepOptions>(received);
    ADD_FAILURE() << "an unknown field was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ms.wire.SweepOptions carries fields this build does not "
                                         "know (numbers 901)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ms
