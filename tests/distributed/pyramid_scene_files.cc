#include "tests/distributed/pyramid_scene_files.h"

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "mesh/mesh_io.h"
#include "scene/scene_h5.h"
#include "sweep/pyramid_geometry.h"
#include "testing/sweep_test_scene.h"

namespace ms::testing {
namespace fs = std::filesystem;

std::string WritePyramidSceneFiles(const std::string& directory,
                                   const PyramidSceneFileOptions& options) {
  PyramidSceneOptions pyramid;
  pyramid.width = options.width;
  pyramid.height = options.height;
  pyramid.noise_stddev = options.noise_stddev;
  const PyramidScene made = MakePyramidScene(pyramid);
  const fs::path dir = fs::absolute(directory);
  fs::create_directories(dir / "images");
  Scene scene;
  scene.source = (dir / "scene.h5").string();
  for (const SweepCamera& camera : made.cameras) {
    View view = camera.view;
    view.name = view.name + ".png";
    view.image_path = (dir / "images" / view.name).string();
    cv::Mat image16;
    camera.image.convertTo(image16, CV_16U, 65535.0);  // saturating: noise may leave [0, 1]
    const fs::path temp = TempPathFor(view.image_path);
    if (!cv::imwrite(temp.string() + ".png", image16)) {
      throw InputError(view.image_path + ": cannot write image");
    }
    CommitTempFile(temp.string() + ".png", view.image_path);
    scene.views.push_back(view);
  }
  for (const Eigen::Vector3d& corner : PyramidBaseCorners()) {
    ScenePoint point;
    point.position = corner;
    for (size_t v = 0; v < scene.views.size(); ++v) {
      Eigen::Vector2d pixel;
      if (!scene.views[v].Project(corner, &pixel)) continue;
      point.observations.push_back(Observation{
          static_cast<int32_t>(v), static_cast<float>(pixel.x()), static_cast<float>(pixel.y())});
    }
    scene.points.push_back(point);
  }
  scene.Validate();
  const std::string path = (dir / "scene.h5").string();
  WriteSceneH5(scene, path);
  WriteMesh(made.truth, (dir / "gt.ply").string());
  return path;
}

}  // namespace ms::testing
