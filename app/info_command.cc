// `manisweep info`: library versions, the OpenGL renderer reachable through EGL, and a scene
// summary when --input is given.
#include <CGAL/version.h>
#include <H5public.h>
#include <google/protobuf/stubs/common.h>
#include <spdlog/version.h>
#include <zmq.h>

#include <Eigen/Core>
#include <cstdio>
#include <memory>
#include <opencv2/core/version.hpp>
#include <string>

#include "app/commands.h"
#include "gl/context.h"
#include "refine/gradient_kernel.h"
#include "scene/scene.h"
#include "scene/scene_io.h"
#include "sweep/sweep_kernel_factory.h"

namespace ms::app {
namespace {

struct InfoOptions {
  std::string input;
  std::string from = "auto";  // scene format name, or auto
  SceneReadOptions read;
};

void RunInfo(const InfoOptions& options) {
  int zmq_major = 0, zmq_minor = 0, zmq_patch = 0;
  zmq_version(&zmq_major, &zmq_minor, &zmq_patch);
  unsigned h5_major = 0, h5_minor = 0, h5_release = 0;
  H5get_libversion(&h5_major, &h5_minor, &h5_release);
  std::printf("manisweep %s\n", MS_VERSION);
  std::printf("  CGAL        %s\n", CGAL_VERSION_STR);
  std::printf("  Eigen       %d.%d.%d\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION,
              EIGEN_MINOR_VERSION);
  std::printf("  OpenCV      %s\n", CV_VERSION);
  std::printf("  Protobuf    %s\n",
              google::protobuf::internal::VersionString(GOOGLE_PROTOBUF_VERSION).c_str());
  std::printf("  ZeroMQ      %d.%d.%d\n", zmq_major, zmq_minor, zmq_patch);
  std::printf("  HDF5        %u.%u.%u\n", h5_major, h5_minor, h5_release);
  std::printf("  spdlog      %d.%d.%d\n", SPDLOG_VER_MAJOR, SPDLOG_VER_MINOR, SPDLOG_VER_PATCH);
  std::printf("  OpenGL      %s\n", gl::DescribeGl().c_str());
  std::string why;
  const std::unique_ptr<SweepKernel> kernel = MakeSweepKernel("auto", {}, &why);
  std::printf("  sweep       kernel '%s' for --kernel auto: %s\n", kernel->Name().c_str(),
              why.c_str());
  const std::unique_ptr<PairGradientKernel> refine = MakePairGradientKernel("auto", &why);
  std::printf("  refine      kernel '%s' for --refine.kernel auto: %s\n", refine->Name().c_str(),
              why.c_str());
  if (!options.input.empty()) {
    const SceneFormat format =
        options.from == "auto" ? DetectSceneFormat(options.input) : ParseSceneFormat(options.from);
    const Scene scene = ReadScene(options.input, options.read, format);
    std::printf("scene %s\n  format      %s\n  %s\n", options.input.c_str(),
                SceneFormatName(format).c_str(), scene.Summary().c_str());
    const BoundingBox box = scene.PointBounds();
    if (!box.Empty()) {
      std::printf("  points in   [%.4g, %.4g] x [%.4g, %.4g] x [%.4g, %.4g]\n", box.min.x(),
                  box.max.x(), box.min.y(), box.max.y(), box.min.z(), box.max.z());
    }
    std::printf("  median viewing distance %.4g\n", scene.MedianViewingDistance());
  }
}

}  // namespace

void RegisterInfoCommand(CLI::App& app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Library versions, the OpenGL renderer available through EGL, and a scene summary");
  cmd->add_option("-i,--input", options->input, "scene to summarise (any supported format)");
  cmd->add_option("--from", options->from, "scene format (see `manisweep convert --help`)")
      ->capture_default_str();
  cmd->add_option("--image-dir", options->read.image_dir,
                  "folder with the images when they are not beside the scene");
  cmd->callback([options] { RunInfo(*options); });
}

}  // namespace ms::app
