// `manisweep keygen`: a CURVE key pair for securing coordinator <-> worker traffic.
#include <spdlog/spdlog.h>

#include <memory>
#include <string>

#include "app/commands.h"
#include "proto/zmq_transport.h"

namespace ms::app {
namespace {

struct KeygenOptions {
  std::string output;
  bool force = false;
};

void RunKeygen(const KeygenOptions& options) {
  RequireCurve("keygen");
  const CurveKeyPair keys = GenerateCurveKeyPair();
  WriteCurveKeyFiles(keys, options.output, options.force);
  spdlog::info(
      "wrote {0}.key (public: give it to the other side) and {0}.key_secret (secret, "
      "mode 600)",
      options.output);
}

}  // namespace

void RegisterKeygenCommand(CLI::App& app) {
  auto options = std::make_shared<KeygenOptions>();
  CLI::App* cmd = app.add_subcommand(
      "keygen",
      "Make a ZeroMQ CURVE key pair (NAME.key, NAME.key_secret) for `coordinator` "
      "and `worker`");
  cmd->add_option("-o,--output", options->output, "NAME: writes NAME.key and NAME.key_secret")
      ->required();
  cmd->add_flag("--force", options->force, "replace existing files");
  cmd->callback([options] { RunKeygen(*options); });
}

}  // namespace ms::app
