// A ground-truth-free quality figure for a mesh of a real scene: for every camera C, the mesh is
// rendered into C, each neighbour's image is reprojected into C through it (the sweep at offset 0,
// by the CPU kernel's slab: sweep/cpu_sweep.h), and the Gaussian-weighted NCC against C's own
// image is computed per pixel (the sweep's window, texture and occlusion rules).
//
// A pixel is consistent if its NCC with at least one neighbour is above the threshold. The
// headline share counts every pixel of every image (pixels the mesh misses, textureless pixels and
// occluded ones count against it, so a mesh cannot score by covering less); the shares among
// covered pixels and among pixels with a defined NCC follow. Pixels are those of the swept
// resolution (SweepOptions::max_image_dimension, as the sweep).
//
// Restricted to the pixels another mesh covers (`within`, e.g. a peer's open mesh), a closed mesh
// and an open one are compared on the same pixels: every count is then of those pixels only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "scene/scene.h"
#include "scene/view_selection.h"
#include "sweep/sweep_options.h"

namespace ms {

struct ConsistencyOptions {
  double ncc_threshold = 0.8;
  SweepOptions sweep;  // num_offsets is ignored: offset 0 only
  NeighbourOptions neighbours;
};

struct CameraConsistency {
  int camera = -1;
  int64_t pixels = 0;      // of the image at the swept resolution
  int64_t covered = 0;     // where the mesh is drawn
  int64_t defined = 0;     // with an NCC against at least one neighbour
  int64_t consistent = 0;  // NCC above the threshold against at least one neighbour
};

struct ConsistencyReport {
  std::vector<CameraConsistency> cameras;  // cameras without a neighbour are left out
  CameraConsistency total;                 // sums (camera -1)
  double ConsistentShare() const;          // consistent / pixels: the headline
  std::string ToTable() const;             // one line per camera and the total
};

// Throws InputError for a bad scene, mesh or image (naming it). With `within`, only the pixels
// that mesh covers count.
ConsistencyReport MeasureConsistency(const Scene& scene, const Mesh& mesh,
                                     const ConsistencyOptions& options,
                                     const Mesh* within = nullptr);

}  // namespace ms
