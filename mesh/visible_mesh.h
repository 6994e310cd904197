// The part of a mesh a camera may see, for a sweep job: faces inside the camera's frustum that
// face the camera. Occlusion is not decided here; the sweep settles it by depth testing.
// Shared code: the coordinator calls it to build sweep jobs.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "base/options.h"
#include "mesh/mesh.h"
#include "scene/camera.h"

namespace ms {

struct VisibleMeshOptions {
  static constexpr const char* kOptionGroup = "visible";
#define MS_OPTION_LIST "mesh/visible_mesh_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

struct VisibleMesh {
  Mesh mesh;                        // compact: only kept faces and the vertices they use
  std::vector<int32_t> face_ids;    // original face index of each face of `mesh`
  std::vector<int32_t> vertex_ids;  // original vertex index of each vertex of `mesh`
};

// True if triangle (a, b, c) (world coordinates) is not entirely outside one plane of the
// view's pinhole frustum (near plane at `near`, image rectangle widened by `margin_px`). A
// conservative test: a face that straddles a corner of the frustum may be kept.
bool TriangleInFrustum(const View& view, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                       const Eigen::Vector3d& c, double margin_px = 0, double near = 0);

// True if the face's front side (counter-clockwise side, docs/reference/conventions.md) faces the
// camera centre. Degenerate faces face nothing.
bool TriangleFacesCamera(const View& view, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c);

// Faces of `mesh` inside the frustum of `view` and facing it, re-indexed into a compact mesh
// (vertex colours kept). Throws InputError if a face refers to a missing vertex.
VisibleMesh ExtractVisibleMesh(const Mesh& mesh, const View& view,
                               const VisibleMeshOptions& options = {});

// The visible meshes of many cameras of one mesh (a sweep iteration's jobs): the faces grouped
// into blocks of nearby faces, each with a bounding box, so that a camera costs O(blocks + kept
// faces) instead of O(faces). Extract returns exactly what ExtractVisibleMesh returns: a block is
// skipped only when its box, widened by far more than rounding, lies outside one frustum plane,
// and then every vertex in it does too.
class VisibleMeshIndex {
 public:
  // Keeps a reference to `mesh`, which must outlive the index and stay unchanged. Throws
  // InputError as ExtractVisibleMesh does for a face referring to a missing vertex.
  explicit VisibleMeshIndex(const Mesh& mesh);
  // Safe to call from several threads at once.
  VisibleMesh Extract(const View& view, const VisibleMeshOptions& options = {}) const;
  size_t num_blocks() const { return blocks_.size(); }

 private:
  struct Block {
    Eigen::Vector3d centre, half;  // bounding box, widened
    int32_t begin = 0, end = 0;    // range of order_
  };
  const Mesh& mesh_;
  std::vector<int32_t> order_;  // face ids, block after block
  std::vector<Block> blocks_;
};

}  // namespace ms
