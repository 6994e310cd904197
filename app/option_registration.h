// Command-line (and --config TOML) registration of option groups (base/options.h): every option
// of a group becomes a flag named as its spec says, with its help and default, so every command
// that takes a group takes all of it, under the same names.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <type_traits>

#include "base/options.h"

namespace ms::app {

// The names of an enum option's values, for CLI11's transformer (ignoring case).
template <typename E>
const std::map<std::string, E>& ChoiceMap(E value) {
  static const std::map<std::string, E> names = [value] {
    std::map<std::string, E> m;
    for (const auto& [name, v] : OptionChoices(value)) m.emplace(name, v);
    return m;
  }();
  return names;
}

// Registers every option of `options` on `command`; values are checked by the group's Check(),
// which the command's callback runs.
template <typename Options>
void AddOptionGroup(CLI::App* command, Options* options) {
  Options::ForEachOption(*options, [command](auto& value, const OptionSpec& spec) {
    using T = std::decay_t<decltype(value)>;
    if constexpr (std::is_same_v<T, bool>) {
      command->add_flag(spec.Flag(), value, spec.help);
    } else if constexpr (std::is_enum_v<T>) {
      command->add_option(spec.Flag(), value, spec.help)
          ->transform(CLI::CheckedTransformer(ChoiceMap(value), CLI::ignore_case)
                          .description("{" + OptionChoiceList(value) + "}"))
          ->default_str(OptionValueText(value));
    } else {
      command->add_option(spec.Flag(), value, spec.help)->capture_default_str();
    }
  });
}

}  // namespace ms::app
