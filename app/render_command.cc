// `manisweep render`: shaded pictures of meshes from a camera of a scene, side by side.
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "app/commands.h"
#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "gl/context.h"
#include "mesh/mesh_io.h"
#include "scene/scene_io.h"
#include "tools/render.h"

namespace ms::app {
namespace {

struct RenderCommandOptions {
  std::vector<std::string> meshes;
  std::string input;
  int camera = 0;
  std::string output;
  ShadedRenderOptions render;
};

void RunRender(const RenderCommandOptions& options) {
  options.render.Check();
  const Scene scene = ReadScene(options.input);
  if (options.camera < 0 || options.camera >= static_cast<int>(scene.views.size())) {
    throw InputError("--camera: " + std::to_string(options.camera) + " is not a view of " +
                     options.input + " (" + std::to_string(scene.views.size()) + " views)");
  }
  const gl::GlContext gl;
  std::vector<cv::Mat> panels;
  for (const std::string& path : options.meshes) {
    cv::Mat panel = RenderShaded(gl, ReadMesh(path), scene.views[options.camera], options.render);
    const std::string label = std::filesystem::path(path).filename().string();
    cv::putText(panel, label, {12, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.8, {255, 255, 255}, 2,
                cv::LINE_AA);
    panels.push_back(panel);
  }
  cv::Mat picture;
  cv::hconcat(panels, picture);
  std::vector<uchar> png;
  if (!cv::imencode(".png", picture, png)) throw InternalError("PNG encoding failed");
  WriteFileAtomically(options.output, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
  spdlog::info("wrote {} ({} x {}, {} mesh(es) from view {})", options.output, picture.cols,
               picture.rows, panels.size(), options.camera);
}

}  // namespace

void RegisterRenderCommand(CLI::App& app) {
  auto options = std::make_shared<RenderCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Shaded pictures of meshes seen from a camera of a scene, side by side (PNG); "
      "faces seen from behind are red");
  cmd->add_option("-m,--mesh", options->meshes, "mesh(es) to render (.ply/.obj)")->required();
  cmd->add_option("-i,--input", options->input, "scene with the camera (any format)")->required();
  cmd->add_option("-c,--camera", options->camera, "view to render from")->capture_default_str();
  cmd->add_option("-o,--output", options->output, "PNG to write")->required();
  cmd->add_option("--max-size", options->render.max_size,
                  "longest side of each picture in pixels (0 = the camera's image size)")
      ->capture_default_str();
  cmd->callback([options] { RunRender(*options); });
}

}  // namespace ms::app
