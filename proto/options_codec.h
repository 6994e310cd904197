// Option groups (base/options.h) to and from their wire messages, field by field through
// protobuf reflection: the message has one field per option, named as the struct's member and of
// the matching type, so adding an option to the group's list and a field to the .proto is all
// it takes. OptionGroupMismatches says where a message and a group disagree (tested for every
// group that travels; a mismatch found at run time is a programming error).
#pragma once

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <google/protobuf/unknown_field_set.h>

#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "base/check.h"
#include "base/error.h"
#include "base/options.h"

namespace ms {
namespace options_codec_internal {

using google::protobuf::FieldDescriptor;

template <typename T>
constexpr FieldDescriptor::CppType WireType() {
  if constexpr (std::is_same_v<T, bool>) return FieldDescriptor::CPPTYPE_BOOL;
  if constexpr (std::is_same_v<T, int32_t>) return FieldDescriptor::CPPTYPE_INT32;
  if constexpr (std::is_same_v<T, int64_t>) return FieldDescriptor::CPPTYPE_INT64;
  if constexpr (std::is_same_v<T, uint32_t>) return FieldDescriptor::CPPTYPE_UINT32;
  if constexpr (std::is_same_v<T, uint64_t>) return FieldDescriptor::CPPTYPE_UINT64;
  if constexpr (std::is_same_v<T, double>) return FieldDescriptor::CPPTYPE_DOUBLE;
  if constexpr (std::is_same_v<T, float>) return FieldDescriptor::CPPTYPE_FLOAT;
  if constexpr (std::is_same_v<T, std::string>) return FieldDescriptor::CPPTYPE_STRING;
  static_assert(!std::is_enum_v<T>, "enum options do not travel (yet): give them a wire form");
  return FieldDescriptor::CPPTYPE_STRING;
}

// The field that carries `spec`, checked (a mismatch is a programming error).
template <typename T>
const FieldDescriptor* Field(const google::protobuf::Message& message, const OptionSpec& spec) {
  const FieldDescriptor* field = message.GetDescriptor()->FindFieldByName(spec.field);
  MS_CHECK(field != nullptr && !field->is_repeated() && field->cpp_type() == WireType<T>())
      << message.GetDescriptor()->full_name() << " has no field '" << spec.field
      << "' of the option's type";
  return field;
}

}  // namespace options_codec_internal

template <typename Options>
void OptionsToWire(const Options& options, google::protobuf::Message* out) {
  using options_codec_internal::Field;
  const google::protobuf::Reflection* r = out->GetReflection();
  Options::ForEachOption(options, [&](const auto& value, const OptionSpec& spec) {
    using T = std::decay_t<decltype(value)>;
    const auto* f = Field<T>(*out, spec);
    if constexpr (std::is_same_v<T, bool>)
      r->SetBool(out, f, value);
    else if constexpr (std::is_same_v<T, int32_t>)
      r->SetInt32(out, f, value);
    else if constexpr (std::is_same_v<T, int64_t>)
      r->SetInt64(out, f, value);
    else if constexpr (std::is_same_v<T, uint32_t>)
      r->SetUInt32(out, f, value);
    else if constexpr (std::is_same_v<T, uint64_t>)
      r->SetUInt64(out, f, value);
    else if constexpr (std::is_same_v<T, double>)
      r->SetDouble(out, f, value);
    else if constexpr (std::is_same_v<T, float>)
      r->SetFloat(out, f, value);
    else
      r->SetString(out, f, value);
  });
}

// Field by field; the result still needs Check() (values come from the network). Throws
// InputError for a field this build does not know: a newer sender's option would otherwise be
// dropped without a word, and the job run with its default.
template <typename Options>
Options OptionsFromWire(const google::protobuf::Message& message) {
  using options_codec_internal::Field;
  Options options;
  const google::protobuf::Reflection* r = message.GetReflection();
  const google::protobuf::UnknownFieldSet& unknown = r->GetUnknownFields(message);
  if (!unknown.empty()) {
    std::string numbers;
    for (int i = 0; i < unknown.field_count(); ++i) {
      numbers += (i > 0 ? ", " : "") + std::to_string(unknown.field(i).number());
    }
    throw InputError(message.GetDescriptor()->full_name() + " carries fields this build does not " +
                     "know (numbers " + numbers + "): the sender runs a newer manisweep; run " +
                     "the same version everywhere");
  }
  Options::ForEachOption(options, [&](auto& value, const OptionSpec& spec) {
    using T = std::decay_t<decltype(value)>;
    const auto* f = Field<T>(message, spec);
    if constexpr (std::is_same_v<T, bool>)
      value = r->GetBool(message, f);
    else if constexpr (std::is_same_v<T, int32_t>)
      value = r->GetInt32(message, f);
    else if constexpr (std::is_same_v<T, int64_t>)
      value = r->GetInt64(message, f);
    else if constexpr (std::is_same_v<T, uint32_t>)
      value = r->GetUInt32(message, f);
    else if constexpr (std::is_same_v<T, uint64_t>)
      value = r->GetUInt64(message, f);
    else if constexpr (std::is_same_v<T, double>)
      value = r->GetDouble(message, f);
    else if constexpr (std::is_same_v<T, float>)
      value = r->GetFloat(message, f);
    else
      value = r->GetString(message, f);
  });
  return options;
}

// Where the group's options and the message's fields disagree: an option without a field of
// its name and type, or a field without an option. Empty when they agree field by field.
template <typename Options>
std::vector<std::string> OptionGroupMismatches(const google::protobuf::Message& message) {
  using options_codec_internal::WireType;
  std::vector<std::string> problems;
  const google::protobuf::Descriptor* d = message.GetDescriptor();
  int matched = 0;
  Options::ForEachOption(Options{}, [&](const auto& value, const OptionSpec& spec) {
    using T = std::decay_t<decltype(value)>;
    const google::protobuf::FieldDescriptor* f = d->FindFieldByName(spec.field);
    if (f == nullptr) {
      problems.push_back(d->full_name() + " has no field " + spec.field);
    } else if (f->is_repeated() || f->cpp_type() != WireType<T>()) {
      problems.push_back(d->full_name() + "." + spec.field + " is not of the option's type");
    } else {
      ++matched;
    }
  });
  if (matched != d->field_count()) {
    for (int i = 0; i < d->field_count(); ++i) {
      bool known = false;
      Options::ForEachOption(Options{}, [&](const auto&, const OptionSpec& spec) {
        known = known || d->field(i)->name() == spec.field;
      });
      if (!known) problems.push_back(d->field(i)->full_name() + " is no option of the group");
    }
  }
  return problems;
}

}  // namespace ms
