// Geometry, materials and camera layouts of the synthetic scenes (no GL, no randomness other than
// the seed given). synth.h turns them into datasets.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "gl/mesh_renderer.h"
#include "mesh/mesh.h"
#include "scene/camera.h"
#include "sweep/pyramid_geometry.h"  // the pyramid scenes' geometry, PyramidBaseSquare

namespace ms {

enum class SynthSceneKind { kPyramidDown, kPyramidUp, kBlob, kCity };

// "pyramid-down", "pyramid-up", "blob", "city"; throws InputError naming the choices.
SynthSceneKind ParseSynthScene(const std::string& name);
std::string SynthSceneName(SynthSceneKind kind);

struct SynthGeometry {
  Mesh mesh;                   // the ground truth, faces counter-clockwise from free space
  gl::SurfaceTexture texture;  // materials and per-face material (photos filled by synth.cc)
  std::vector<View> views;     // names "0000.png", ...
  Mesh initial_mesh;           // pyramids: the base square (the paper's initial manifold)
  std::vector<Eigen::Vector3d> fixed_points;  // pyramids: the 4 base corners, seen by all views
  double max_view_distance = 0;  // sparse points farther than this from a camera are not seen
  int evaluation_view = 0;       // the paper's "first camera"
};

struct SynthLayout {
  int views = 16;
  int width = 800;
  int height = 600;
  uint64_t seed = 1;
};

// Square-based pyramid (sweep/pyramid_geometry.h), base 2 m x 2 m at z = 0 without its base
// facet, height 0.3 m, apex at z = -0.3 (down) or +0.3 (up); cameras above (z > 0) on a cap
// around the vertical axis at 1.2 m from the centre; each view's focal length frames the whole
// pyramid.
SynthGeometry MakePyramidScene(bool apex_up, const SynthLayout& layout);
// Closed bumpy blob of radius ~1 (shape from the seed), cameras on two interleaved rings.
SynthGeometry MakeBlobScene(const SynthLayout& layout);
// Ground + building blocks along a street (x axis); cameras walk the street in pairs looking
// left and right; the street grows with the number of views (1.5 m per pair).
SynthGeometry MakeCityScene(const SynthLayout& layout);

SynthGeometry MakeSynthGeometry(SynthSceneKind kind, const SynthLayout& layout);

// Camera at `center` looking at `target`, image y pointing away from `up` (x_cam right).
View LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target, const Eigen::Vector3d& up,
            const Intrinsics& intrinsics);

// The largest focal length (fx = fy, centred principal point) at which every point projects
// inside every view with `margin` (share of the half-size) left free. Points must be in front.
double FitFocalLength(const std::vector<View>& views, const std::vector<Eigen::Vector3d>& points,
                      double margin);

}  // namespace ms
