#include "app/distributed_options.h"

#include "app/option_registration.h"

namespace ms::app {

void AddRunOptions(CLI::App* command, CoordinatorOptions* options) {
  AddOptionGroup(command, &options->run);
  AddOptionGroup(command, &options->manifold);
  AddOptionGroup(command, &options->neighbours);
  AddOptionGroup(command, &options->visible);
  AddOptionGroup(command, &options->scheduler);
  AddOptionGroup(command, &options->sweep);
}

}  // namespace ms::app
