// openMVG sfm_data.json from memory.
#include <cstdint>

#include "base/error.h"
#include "fuzz_util.h"
#include "scene/openmvg_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string root;
  try {
    ms::ParseOpenMvg("sfm_data.json", std::string(reinterpret_cast<const char*>(data), size), &root)
        .Validate();
  } catch (const ms::InputError&) {
  }
  return 0;
}
