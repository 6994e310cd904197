// Option groups shared by several commands, so a name means the same everywhere (and in a
// --config file): --manifold.* here.
#pragma once

#include <CLI/CLI.hpp>

#include "manifold/manifold_options.h"

namespace ms::app {

void RegisterManifoldOptions(CLI::App* command, ManifoldOptions* options);

}  // namespace ms::app
