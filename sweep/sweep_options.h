// Options of the mesh sweep (paper section 2.2, docs/sweep.md), sent with every job.
#pragma once

namespace ms {

struct SweepOptions {
  // N: sweep positions k with -N/2 < k < N/2 (N = 20 gives k = -9..9, 19 swept meshes).
  int num_offsets = 20;
  // alpha: sweep step in scene units (facet vertex v moves by alpha*k*|cos(theta)| along C's
  // ray). 0 = derive from the job (alpha_parallax_px below; docs/sweep.md). The paper's 3 cm is
  // alpha = 0.03 for a scene in metres.
  double alpha = 0;
  // Automatic alpha: one step moves a point at the job's median depth by this many pixels of
  // parallax in the neighbour images (pixels of the swept resolution).
  double alpha_parallax_px = 1.0;
  // t_NCC: a tile's best pixel becomes a point only if its NCC is strictly above this.
  double ncc_threshold = 0.98;
  // sigma of the Gaussian NCC window, in pixels of the swept resolution.
  double gaussian_sigma_px = 8;
  // Target tile size in pixels of the swept resolution; the image is split into
  // round(W/size) x round(H/size) tiles (at least 1 x 1).
  int tile_size_px = 100;
  // Pixels whose weighted variance in C's image or in the reprojected image is below this are
  // textureless and never match (images are gray in [0, 1]; 1e-4 is a std of 2.55/255).
  double min_texture_variance = 1e-4;
  // A pixel's NCC counts only if the valid pixels carry at least this fraction of the Gaussian
  // window's weight (the window is cut by the mesh's silhouette, the images' borders, occlusion).
  double min_window_weight = 0.5;
  // Occlusion test in a neighbour: a point is visible if its depth is at most the shadow map's
  // depth times (1 + this).
  double occlusion_tolerance = 0.01;
  // Resolution: images larger than this (longest side, pixels) are swept at a pyramid level,
  // halving until they fit (3072x2048 -> 1536x1024). 0 = always full size.
  int max_image_dimension = 1600;
  // Pyramid level to sweep at: -1 = choose from max_image_dimension; 0 = full size; L = images
  // and intrinsics scaled by 2^-L.
  int pyramid_level = -1;
  void Check() const;  // throws InputError naming the field
};

}  // namespace ms
