// Shared bits of the scene-format fuzz targets: fixture files to pair a fuzzed file with, and a
// splitter for inputs that stand for several files.
#pragma once

#include <spdlog/spdlog.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/file_util.h"

namespace ms::fuzz {

// Readers log warnings (e.g. repeated views in a track); at thousands of inputs a second that
// would be most of the work.
inline const bool kQuiet = (spdlog::set_level(spdlog::level::off), true);

inline std::string Fixture(const std::string& relative) {
  return ReadFileToString(std::string(MS_SOURCE_DIR) + "/tests/data/" + relative);
}

// Splits `data` at each "@@@" (at most `parts` pieces; missing pieces are empty).
inline std::vector<std::string> Split(const uint8_t* data, size_t size, size_t parts) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> out;
  size_t start = 0;
  while (out.size() + 1 < parts) {
    const size_t at = all.find("@@@", start);
    if (at == std::string::npos) break;
    out.push_back(all.substr(start, at - start));
    start = at + 3;
  }
  out.push_back(all.substr(start));
  out.resize(parts);
  return out;
}

}  // namespace ms::fuzz
