#include "shaders/shaders.h"

#include <algorithm>
#include <set>

#include "base/error.h"
#include "shaders/shaders_internal.h"

namespace ms::shaders {
namespace {

const internal::EmbeddedShader* Find(std::string_view name) {
  for (int i = 0; i < internal::kNumEmbeddedShaders; ++i) {
    if (name == internal::kEmbeddedShaders[i].name) return &internal::kEmbeddedShaders[i];
  }
  return nullptr;
}

// `#include "x"` (spaces allowed before and after '#'); returns x or an empty view.
std::string_view IncludeTarget(std::string_view line) {
  size_t i = line.find_first_not_of(" \t");
  if (i == std::string_view::npos || line[i] != '#') return {};
  i = line.find_first_not_of(" \t", i + 1);
  if (i == std::string_view::npos || line.substr(i, 7) != "include") return {};
  const size_t open = line.find('"', i + 7);
  if (open == std::string_view::npos) return {};
  const size_t close = line.find('"', open + 1);
  if (close == std::string_view::npos) return {};
  return line.substr(open + 1, close - open - 1);
}

void ExpandInto(std::string_view name, int string_number, std::vector<std::string>* names,
                std::set<std::string>* stack, std::string* out) {
  const std::string_view text = Source(name);
  size_t pos = 0;
  int line_number = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    const std::string_view target = IncludeTarget(line);
    if (target.empty()) {
      out->append(line);
      out->push_back('\n');
      continue;
    }
    const std::string target_name(target);
    if (stack->count(target_name)) {
      throw InternalError("shader '" + std::string(name) + "' line " + std::to_string(line_number) +
                          ": recursive #include \"" + target_name + "\"");
    }
    if (std::find(names->begin(), names->end(), target_name) == names->end()) {
      names->push_back(target_name);
      const int number = static_cast<int>(names->size()) - 1;
      stack->insert(target_name);
      out->append("#line 1 " + std::to_string(number) + "\n");
      ExpandInto(target_name, number, names, stack, out);
      stack->erase(target_name);
    }
    out->append("#line " + std::to_string(line_number + 1) + " " + std::to_string(string_number) +
                "\n");
  }
}

}  // namespace

std::string_view Source(std::string_view name) {
  if (const internal::EmbeddedShader* shader = Find(name)) return shader->source;
  std::string known;
  for (std::string_view n : Names()) known += (known.empty() ? "" : ", ") + std::string(n);
  throw InternalError("no embedded shader named '" + std::string(name) + "' (known: " + known +
                      ")");
}

bool Has(std::string_view name) { return Find(name) != nullptr; }

std::vector<std::string_view> Names() {
  std::vector<std::string_view> names;
  for (int i = 0; i < internal::kNumEmbeddedShaders; ++i) {
    names.emplace_back(internal::kEmbeddedShaders[i].name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string Expand(std::string_view name, std::vector<std::string>* included_names) {
  std::vector<std::string> names{std::string(name)};
  std::set<std::string> stack{std::string(name)};
  std::string out;
  ExpandInto(name, 0, &names, &stack, &out);
  if (included_names) *included_names = std::move(names);
  return out;
}

}  // namespace ms::shaders
