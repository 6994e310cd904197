// NVM from memory; the first byte picks the model index (0-2). Image sizes are fixed.
#include <cstdint>

#include "base/error.h"
#include "fuzz_util.h"
#include "scene/nvm_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  try {
    ms::ParseNvm("fuzz.nvm", std::string(reinterpret_cast<const char*>(data) + 1, size - 1),
                 data[0] % 3,
                 [](const std::string&) {
                   return ms::ImageSize{64, 48};
                 })
        .Validate();
  } catch (const ms::InputError&) {
  }
  return 0;
}
