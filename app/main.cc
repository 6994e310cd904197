// manisweep: one binary, many commands. See `manisweep help`.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "app/commands.h"
#include "base/error.h"
#include "base/log.h"

int main(int argc, char** argv) {
  ms::InitLogging();
  CLI::App app{
      "manisweep: manifold meshes from Structure-from-Motion, by Delaunay triangulation and "
      "GPU mesh sweeping (Romanoni et al., WACV 2016).",
      "manisweep"};
  app.require_subcommand(0, 1);
  app.fallthrough();  // global options may follow the command name
  app.set_config("--config", "",
                 "TOML/INI file with options ([command] sections); the command line overrides it");
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->capture_default_str();
  app.parse_complete_callback([&] { ms::SetLogLevel(log_level); });

  auto* help = app.add_subcommand("help", "Show this help, or `help <command>`");
  std::string help_topic;
  help->add_option("command", help_topic, "command to describe");

  ms::app::RegisterInfoCommand(app);
  ms::app::RegisterManifoldCommand(app);
  ms::app::RegisterCheckMeshCommand(app);
  ms::app::RegisterSweepCommand(app);
  ms::app::RegisterSynthCommand(app);
  ms::app::RegisterEvaluateCommand(app);
  ms::app::RegisterConvertCommand(app);
  ms::app::RegisterReconstructCommand(app);
  ms::app::RegisterCoordinatorCommand(app);
  ms::app::RegisterWorkerCommand(app);
  ms::app::RegisterKeygenCommand(app);
  ms::app::RegisterColmapTriangulateCommand(app);

  try {
    app.parse(argc, argv);
    if (app.got_subcommand(help) || app.get_subcommands().empty()) {
      if (!help_topic.empty()) {
        CLI::App* sub = nullptr;
        try {
          sub = app.get_subcommand(help_topic);
        } catch (const CLI::OptionNotFound&) {
          throw ms::InputError("help: unknown command '" + help_topic + "'");
        }
        std::fputs(sub->help().c_str(), stdout);
      } else {
        std::fputs(app.help().c_str(), stdout);
      }
    }
  } catch (const ms::app::CommandExit& e) {
    return e.code();
  } catch (const CLI::CallForHelp&) {
    // --help on the app or a subcommand: print the help of the one asked.
    const CLI::App* target = &app;
    for (const CLI::App* sub : app.get_subcommands()) target = sub;
    std::fputs(target->help().c_str(), stdout);
    return ms::kExitOk;
  } catch (const CLI::CallForAllHelp&) {
    std::fputs(app.help("", CLI::AppFormatMode::All).c_str(), stdout);
    return ms::kExitOk;
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "manisweep: %s (see `manisweep help`)\n", e.what());
    return ms::kExitBadInput;
  } catch (const ms::InputError& e) {
    std::fprintf(stderr, "manisweep: error: %s\n", e.what());
    return ms::kExitBadInput;
  } catch (const ms::InternalError& e) {
    std::fprintf(stderr, "manisweep: internal error: %s\n", e.what());
    return ms::kExitInternal;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "manisweep: internal error: out of memory\n");
    return ms::kExitInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "manisweep: internal error: %s\n", e.what());
    return ms::kExitInternal;
  }
  return ms::kExitOk;
}
