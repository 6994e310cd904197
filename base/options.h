// Option groups declared once. Each group (ManifoldOptions, SweepOptions, ...) lists its options
// in a *_options_def.h file, one MS_OPTION(type, name, default, flag, help, bound) line each, in
// the style of Ray's ray_config_def.h. base/option_group_members.h expands that list inside the
// group's struct twice: once to declare the fields, once to define ForEachOption, which hands
// every field to a visitor with its OptionSpec. Everything else is derived from that one list:
//   - Check() (CheckOptionGroup below): bounds, in the user's words ("--sweep.ncc-threshold must
//     be in [-1, 1], got 1.5", the form of Ceres' OPTION_GE);
//   - the command-line and TOML registration (app/option_registration.h);
//   - the run fingerprint (OptionGroupText below);
//   - the wire codec (proto/options_codec.h, by protobuf reflection on the field names).
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "base/error.h"

namespace ms {

// The values an option may take. Numbers only; enums are bounded by their choices (below),
// strings and booleans by nothing.
struct OptionBound {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;

  bool Contains(double v) const {
    if (!std::isfinite(v)) return false;
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  // ">= 0", "> 0", "in [1, 1000]", "in (0, 1]"; "" when unbounded.
  std::string Describe() const {
    const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
    if (has_lo && has_hi) {
      return fmt::format("in {}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
    }
    if (has_lo) return fmt::format("{} {}", lo_open ? ">" : ">=", lo);
    if (has_hi) return fmt::format("{} {}", hi_open ? "<" : "<=", hi);
    return "";
  }
};

constexpr OptionBound AnyValue() { return {}; }
constexpr OptionBound AtLeast(double lo) {
  return {lo, std::numeric_limits<double>::infinity(), false, false};
}
constexpr OptionBound Above(double lo) {
  return {lo, std::numeric_limits<double>::infinity(), true, false};
}
constexpr OptionBound InRange(double lo, double hi) { return {lo, hi, false, false}; }  // [lo, hi]
constexpr OptionBound InRangeOpenLow(double lo, double hi) { return {lo, hi, true, false}; }
constexpr OptionBound InRangeOpenHigh(double lo, double hi) { return {lo, hi, false, true}; }

// One option of a group, as its visitor sees it.
struct OptionSpec {
  const char* group;  // "manifold": the flag's prefix, "" for top-level flags (--lease)
  const char* field;  // the C++ member, and the field of the .proto message that carries it
  const char* flag;   // "w1" -> --manifold.w1
  const char* help;
  OptionBound bound;

  // "--manifold.w1"; the command line and the messages use it.
  std::string Flag() const {
    return *group ? fmt::format("--{}.{}", group, flag) : fmt::format("--{}", flag);
  }
  // "manifold.w1": the key in a --config file's command section.
  std::string Key() const { return Flag().substr(2); }
};

// An enum option's names: a group that uses enum E declares, in E's namespace,
//   const std::vector<std::pair<const char*, E>>& OptionChoices(E);
// found by argument-dependent lookup.
template <typename E>
const char* OptionChoiceName(E value) {
  for (const auto& [name, v] : OptionChoices(value)) {
    if (v == value) return name;
  }
  return nullptr;
}

template <typename E>
std::string OptionChoiceList(E value) {
  std::string list;
  for (const auto& [name, v] : OptionChoices(value)) {
    (void)v;
    list += (list.empty() ? "" : ", ") + std::string(name);
  }
  return list;
}

// A value as the user types it (and as the fingerprint records it).
template <typename T>
std::string OptionValueText(const T& value) {
  if constexpr (std::is_enum_v<T>) {
    const char* name = OptionChoiceName(value);
    return name ? name : fmt::format("#{}", static_cast<int64_t>(value));
  } else if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else {
    return fmt::format("{}", value);
  }
}

// Throws InputError naming the flag, the rule and the value if `value` breaks the spec.
template <typename T>
void CheckOptionValue(const T& value, const OptionSpec& spec) {
  if constexpr (std::is_enum_v<T>) {
    if (OptionChoiceName(value) == nullptr) {
      throw InputError(fmt::format("{} must be one of {}, got {}", spec.Flag(),
                                   OptionChoiceList(value), OptionValueText(value)));
    }
  } else if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    if (!spec.bound.Contains(static_cast<double>(value))) {
      const std::string rule = spec.bound.Describe();
      throw InputError(fmt::format("{} must be {}, got {}", spec.Flag(),
                                   rule.empty() ? "finite" : rule, OptionValueText(value)));
    }
  }
}

// Check() of every group: each option against its bound, in declaration order.
template <typename Options>
void CheckOptionGroup(const Options& options) {
  Options::ForEachOption(
      options, [](const auto& value, const OptionSpec& spec) { CheckOptionValue(value, spec); });
}

// {"manifold.w1", "4"}, ...: every option of the group with its value as the user types it,
// in declaration order (summary.json and the run report record them).
using OptionValues = std::vector<std::pair<std::string, std::string>>;
template <typename Options>
OptionValues OptionGroupValues(const Options& options) {
  OptionValues values;
  Options::ForEachOption(options, [&](const auto& value, const OptionSpec& spec) {
    values.emplace_back(spec.Key(), OptionValueText(value));
  });
  return values;
}

// "manifold.w1=4 manifold.w2=0.5 ...": every option of the group, for fingerprints and logs.
template <typename Options>
std::string OptionGroupText(const Options& options) {
  std::string text;
  for (const auto& [key, value] : OptionGroupValues(options)) {
    text += fmt::format("{}{}={}", text.empty() ? "" : " ", key, value);
  }
  return text;
}

}  // namespace ms

// A group's struct (e.g. sweep/sweep_options.h):
//   struct SweepOptions {
//     static constexpr const char* kOptionGroup = "sweep";
//   #define MS_OPTION_LIST "sweep/sweep_options_def.h"
//   #include "base/option_group_members.h"
//     void Check() const { CheckOptionGroup(*this); }
//   };
// option_group_members.h expands the list twice with these:
#define MS_OPTION_FIELD(type, name, default_value, flag, help, bound) type name = default_value;
#define MS_OPTION_VISIT(type, name, default_value, flag, help, bound) \
  visit(self.name, ::ms::OptionSpec{kOptionGroup, #name, flag, help, bound});
