// manisweep: one binary, many commands. See `manisweep help`.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "app/commands.h"
#include "base/error.h"
#include "base/log.h"
#include "scene/h5_file.h"

namespace {

// CLI11 reads `manifold.w1 = 5` in a [manifold] section as a nested section "manifold" holding
// "w1". Our option names contain dots (--manifold.w1, --sweep.ncc-threshold), so keep
// everything after the command's section as the option name: the config file then uses the
// command line's names.
class DottedNameConfig : public CLI::ConfigTOML {
 public:
  explicit DottedNameConfig(const CLI::App* app) : app_(app) {}
  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    std::vector<CLI::ConfigItem> items = CLI::ConfigTOML::from_config(input);
    for (CLI::ConfigItem& item : items) {
      if (item.parents.empty() || item.name == "++" || item.name == "--") continue;
      size_t keep = 0;  // leading parents that name a subcommand
      for (const CLI::App* sub : app_->get_subcommands({})) {
        if (sub->get_name() == item.parents[0]) keep = 1;
      }
      if (item.parents.size() <= keep) continue;
      std::string name;
      for (size_t i = keep; i < item.parents.size(); ++i) name += item.parents[i] + ".";
      item.name = name + item.name;
      item.parents.resize(keep);
    }
    return items;
  }

 private:
  const CLI::App* app_;
};

}  // namespace

int main(int argc, char** argv) {
  ms::InitLogging();
  CLI::App app{
      "manisweep: manifold meshes from Structure-from-Motion, by Delaunay triangulation and "
      "GPU mesh sweeping (Romanoni et al., WACV 2016).",
      "manisweep"};
  app.require_subcommand(0, 1);
  app.fallthrough();  // global options may follow the command name
  app.set_config("--config", "",
                 "TOML file with options ([command] sections, the command line's option names); "
                 "the command line overrides it");
  app.config_formatter(std::make_shared<DottedNameConfig>(&app));
  app.allow_config_extras(CLI::config_extras_mode::error);  // a misspelt key is an error
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
  ms::app::RegisterConsistencyCommand(app);
  ms::app::RegisterRenderCommand(app);
  ms::app::RegisterConvertCommand(app);
  ms::app::RegisterReconstructCommand(app);
  ms::app::RegisterExtendCommand(app);
  ms::app::RegisterCoordinatorCommand(app);
  ms::app::RegisterWorkerCommand(app);
  ms::app::RegisterKeygenCommand(app);
  ms::app::RegisterColmapTriangulateCommand(app);
  ms::app::RegisterReportCommand(app);
  ms::app::RegisterRefineCommand(app);

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
        // App::help() would describe the selected subcommand (`help` itself): format the app.
        std::fputs(
            app.get_formatter()->make_help(&app, "manisweep", CLI::AppFormatMode::Normal).c_str(),
            stdout);
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
    if (ms::Hdf5FilesAbandoned()) {
      // A write failed (a full disk): HDF5's clean-up at exit would crash on the file left open.
      std::fflush(nullptr);
      std::_Exit(ms::kExitBadInput);
    }
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
