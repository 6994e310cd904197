// COLMAP text or binary models (FUZZ_COLMAP_BINARY picks which). The first byte chooses which
// file the rest replaces in the valid fixture (cameras, images, points3D), or (3) that the rest
// is all three files separated by "@@@".
#include <cstdint>

#include "base/error.h"
#include "fuzz_util.h"
#include "scene/colmap_io.h"

namespace {
const bool kBinary = FUZZ_COLMAP_BINARY;
const char* const kDir = kBinary ? "colmap/bin/" : "colmap/text/";
const char* const kExt = kBinary ? ".bin" : ".txt";
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const ms::ColmapFiles fixture = [] {
    ms::ColmapFiles f;
    f.cameras = ms::fuzz::Fixture(std::string(kDir) + "cameras" + kExt);
    f.images = ms::fuzz::Fixture(std::string(kDir) + "images" + kExt);
    f.points = ms::fuzz::Fixture(std::string(kDir) + "points3D" + kExt);
    return f;
  }();
  ms::ColmapFiles files = fixture;
  files.cameras_name = "cameras";
  files.images_name = "images";
  files.points_name = "points3D";
  const std::string rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 4) {
    case 0:
      files.cameras = rest;
      break;
    case 1:
      files.images = rest;
      break;
    case 2:
      files.points = rest;
      break;
    default: {
      auto parts = ms::fuzz::Split(data + 1, size - 1, 3);
      files.cameras = parts[0];
      files.images = parts[1];
      files.points = parts[2];
    }
  }
  try {
    ms::ParseColmapModel(std::move(files), kBinary).Validate();
  } catch (const ms::InputError&) {
  }
  return 0;
}
