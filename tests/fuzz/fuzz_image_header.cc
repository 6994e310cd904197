// PNG/JPEG header parsing from memory.
#include <cstdint>
#include <string_view>

#include "base/error.h"
#include "fuzz_util.h"
#include "scene/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ms::ParseImageSize("image", std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const ms::InputError&) {
  }
  return 0;
}
