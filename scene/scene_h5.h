// The scene in HDF5 (scene.h5), manisweep's canonical scene store. Layout: docs/reference/hdf5.md.
//
// Everything round-trips bit for bit: doubles as IEEE float64, pixel coordinates as float32
// (NaN included), colours as uint8. Reading checks the format version, every shape and the
// observation offsets, then Scene::Validate(); any problem throws InputError naming the file and
// the dataset.
#pragma once

#include <cstdint>
#include <string>

#include "scene/scene.h"

namespace ms {

class H5File;

// Written as the "format_version" attribute of the scene group; readers accept only this one.
constexpr int64_t kSceneH5FormatVersion = 1;
// Written as the "format" attribute of the scene group.
inline constexpr char kSceneH5FormatName[] = "manisweep-scene";

// A whole file holding one scene in its root group. Written atomically.
// The read scene's `source` is `path` (for messages); the writer's `source` is kept in the
// "source" attribute (see ReadSceneH5Source).
Scene ReadSceneH5(const std::string& path);
void WriteSceneH5(const Scene& scene, const std::string& path);

// A scene inside a group of an open file (checkpoints hold a scene plus more). The group is
// created if missing; its scene datasets are replaced. "/" is the root group.
void WriteSceneH5(const Scene& scene, H5File& file, const std::string& group);
// The read scene's `source` is "<file>" for the root group, "<file>:<group>" otherwise.
Scene ReadSceneH5(const H5File& file, const std::string& group);

// The "source" attribute: where the stored scene originally came from (e.g. "model.nvm").
std::string ReadSceneH5Source(const H5File& file, const std::string& group);

}  // namespace ms
