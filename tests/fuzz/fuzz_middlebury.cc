// Middlebury *_par.txt from memory. Image sizes are fixed.
#include <cstdint>

#include "base/error.h"
#include "fuzz_util.h"
#include "scene/middlebury_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ms::ParseMiddlebury("x_par.txt", std::string(reinterpret_cast<const char*>(data), size),
                        [](const std::string&) {
                          return ms::ImageSize{640, 480};
                        })
        .Validate();
  } catch (const ms::InputError&) {
  }
  return 0;
}
