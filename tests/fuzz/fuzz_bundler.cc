// Bundler: "bundle.out@@@list.txt" (without "@@@", a three-image list).
#include <cstdint>

#include "base/error.h"
#include "fuzz_util.h"
#include "scene/bundler_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto parts = ms::fuzz::Split(data, size, 2);
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  if (all.find("@@@") == std::string_view::npos) parts[1] = "a.png\nb.png\nc.png\n";
  try {
    ms::ParseBundler("bundle.out", parts[0], "list.txt", parts[1], [](const std::string&) {
      return ms::ImageSize{64, 48};
    }).Validate();
  } catch (const ms::InputError&) {
  }
  return 0;
}
