// One Strecha .camera file from memory.
#include <cstdint>

#include "base/error.h"
#include "fuzz_util.h"
#include "scene/strecha_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ms::Scene scene;
    scene.views.push_back(ms::ParseStrechaCamera(
        "a.png.camera", std::string(reinterpret_cast<const char*>(data), size)));
    scene.Validate();
  } catch (const ms::InputError&) {
  }
  return 0;
}
