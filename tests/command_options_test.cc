// Every command that takes an option group takes all of it: each declared option appears in the
// command's --help, and a value given on the command line or in a --config file reaches the
// option's check. Runs the real `manisweep` binary.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "coordinator/coordinator.h"
#include "manifold/manifold_options.h"
#include "mesh/visible_mesh.h"
#include "report/report_options.h"
#include "scene/view_selection.h"
#include "sweep/sweep_options.h"
#include "testing/testing.h"
#include "worker/worker_process.h"

namespace ms {
namespace {

struct Output {
  int status = -1;
  std::string text;  // stdout and stderr
};

Output RunManisweep(const std::string& args) {
  const std::string command = "'" MANISWEEP_BINARY "' " + args + " 2>&1";
  Output out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    out.text.append(buffer.data(), n);
  out.status = ::pclose(pipe);
  return out;
}

template <typename Options>
std::vector<std::string> Flags() {
  std::vector<std::string> flags;
  Options::ForEachOption(
      Options{}, [&](const auto&, const OptionSpec& spec) { flags.push_back(spec.Flag()); });
  return flags;
}

template <typename... Groups>
std::vector<std::string> FlagsOf() {
  std::vector<std::string> all;
  for (const std::vector<std::string>& flags : {Flags<Groups>()...}) {
    all.insert(all.end(), flags.begin(), flags.end());
  }
  return all;
}

void ExpectHelpListsEveryFlag(const std::string& command, const std::vector<std::string>& flags) {
  const Output help = RunManisweep(command + " --help");
  ASSERT_EQ(help.status, 0) << help.text;
  for (const std::string& flag : flags) {
    // The flag followed by a space or the end of its column (a type, '=default' or the help).
    EXPECT_TRUE(help.text.find("  " + flag + " ") != std::string::npos ||
                help.text.find("  " + flag + "\n") != std::string::npos)
        << "`manisweep " << command << " --help` does not list " << flag;
  }
}

TEST(CommandOptions, ReconstructTakesEveryOptionOfARun) {
  ExpectHelpListsEveryFlag(
      "reconstruct", FlagsOf<RunOptions, ManifoldOptions, NeighbourOptions, VisibleMeshOptions,
                             SchedulerOptions, SweepOptions>());
}

TEST(CommandOptions, CoordinatorTakesEveryOptionOfARun) {
  ExpectHelpListsEveryFlag(
      "coordinator", FlagsOf<RunOptions, ManifoldOptions, NeighbourOptions, VisibleMeshOptions,
                             SchedulerOptions, SweepOptions>());
}

TEST(CommandOptions, ReportReconstructAndCoordinatorTakeEveryReportOption) {
  ExpectHelpListsEveryFlag("report", FlagsOf<ReportOptions>());
  ExpectHelpListsEveryFlag("reconstruct", FlagsOf<ReportOptions>());
  ExpectHelpListsEveryFlag("coordinator", FlagsOf<ReportOptions>());
}

TEST(CommandOptions, ManifoldTakesEveryManifoldOption) {
  ExpectHelpListsEveryFlag("manifold", FlagsOf<ManifoldOptions>());
}

TEST(CommandOptions, SweepTakesEverySweepAndNeighbourOption) {
  ExpectHelpListsEveryFlag("sweep", FlagsOf<NeighbourOptions, SweepOptions>());
}

TEST(CommandOptions, WorkerTakesEveryWorkerOption) {
  ExpectHelpListsEveryFlag("worker", FlagsOf<WorkerOptions>());
}

TEST(CommandOptions, ReconstructAcceptsTheGradedSteinerOptionDocsManifoldMdDocuments) {
  // Once rejected as "arguments were not expected". A later, invalid option stops the run
  // before it starts, which shows the first one was accepted.
  const Output out = RunManisweep("reconstruct --manifold.graded-steiner off --max-iterations -1");
  EXPECT_NE(out.status, 0);
  EXPECT_NE(out.text.find("--max-iterations must be in [0, 1000], got -1"), std::string::npos)
      << out.text;
}

TEST(CommandOptions, BadValuesAreReportedWithTheFlagTheUserTyped) {
  const Output out = RunManisweep("coordinator --input x --output y --visible.margin-px -1");
  EXPECT_EQ(WEXITSTATUS(out.status), 2) << out.text;
  EXPECT_NE(out.text.find("--visible.margin-px must be >= 0, got -1"), std::string::npos)
      << out.text;
}

TEST(CommandOptions, AConfigFileSetsOptionsByTheirDottedNames) {
  const testing::TempDir dir("config");
  std::ofstream(dir / "run.toml") << "[manifold]\nmanifold.steiner-grid = 1\n";
  const Output out =
      RunManisweep("--config " + dir / "run.toml" + " manifold --input x --output y");
  EXPECT_EQ(WEXITSTATUS(out.status), 2) << out.text;
  EXPECT_NE(out.text.find("--manifold.steiner-grid must be in [2, 64], got 1"), std::string::npos)
      << out.text;
}

// `manifold --tiles`: one closed mesh from the tiles, each tile's faces and the layout on
// request; --tile-meshes without --tiles is refused.
TEST(CommandOptions, ManifoldOverTilesWritesOneClosedMeshAndEachTile) {
  const testing::TempDir dir("tiles");
  ASSERT_EQ(RunManisweep("synth blob --no-images --output " + dir / "blob").status, 0);
  const Output out = RunManisweep("manifold --input " + dir / "blob" + "/scene.h5 --output " +
                                  dir / "blob.ply" + " --tiles 3 --tile-meshes " + dir / "tiles");
  ASSERT_EQ(out.status, 0) << out.text;
  EXPECT_NE(out.text.find("over 3 tiles"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("check-mesh        closed 2-manifold"), std::string::npos) << out.text;
  for (const char* name : {"tiles.json", "tile_0.ply", "tile_1.ply", "tile_2.ply"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "tiles" + "/" + name)) << name;
  }
  const Output refused = RunManisweep("manifold --input " + dir / "blob" + "/scene.h5 --output " +
                                      dir / "other.ply" + " --tile-meshes " + dir / "tiles");
  EXPECT_EQ(WEXITSTATUS(refused.status), 2) << refused.text;
  EXPECT_NE(refused.text.find("--tile-meshes needs --tiles"), std::string::npos) << refused.text;
}

}  // namespace
}  // namespace ms
