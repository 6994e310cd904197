#include "app/default_scene.h"

#include <filesystem>

#include "gl/context.h"
#include "tools/synth.h"

namespace ms::app {
namespace fs = std::filesystem;

std::string MakeDefaultScene(const std::string& directory) {
  SynthOptions options;
  options.scene = "pyramid-down";
  options.views = 8;
  options.width = 640;
  options.height = 480;
  const gl::GlContext gl;
  const SynthDataset dataset = MakeSynthDataset(options, &gl);
  WriteSynthDataset(dataset, directory);
  return (fs::absolute(directory) / "scene.h5").string();
}

}  // namespace ms::app
