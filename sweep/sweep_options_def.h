// The options of the mesh sweep (paper section 2.2, docs/design/sweep.md), one line each:
//   MS_OPTION(type, name, default, flag, help, bound)
// Expanded by base/option_group_members.h in sweep/sweep_options.h (no include guard); the wire
// message ms.wire.SweepOptions in proto/manisweep.proto has one field of the same name per line.

// N: sweep positions k with -N/2 < k < N/2 (N = 20 gives k = -9..9, 19 swept meshes).
MS_OPTION(int, num_offsets, 20, "num-offsets", "N: sweep offsets k with -N/2 < k < N/2",
          InRange(1, 1000))
// alpha: facet vertex v moves by alpha*k*|cos(theta)| along C's ray. The paper's 3 cm is 0.03
// for a scene in metres; 0 derives it from the job (alpha_parallax_px).
MS_OPTION(double, alpha, 0, "alpha",
          "sweep step in scene units; 0 = auto from the parallax (0.03 = the paper's 3 cm in a "
          "metric scene)",
          AtLeast(0))
// One automatic step moves a point at the job's median depth by this many pixels of parallax in
// the neighbour images (pixels of the swept resolution).
MS_OPTION(double, alpha_parallax_px, 1.0, "alpha-parallax-px",
          "auto alpha: pixels of parallax in the neighbours per step at the median depth", Above(0))
// t_NCC: a tile's best pixel becomes a point only if its NCC is strictly above this.
MS_OPTION(double, ncc_threshold, 0.98, "ncc-threshold", "t_NCC: keep tile winners above this",
          InRange(-1, 1))
// A pixel matched by one neighbour alone is an outlier far more often than one matched by
// two (docs/design/sweep.md "Matching neighbours" measures it). 0 and 1 both mean any one neighbour
// (the paper); jobs with fewer neighbours, or pixels fewer neighbours see, need all of theirs.
MS_OPTION(int, min_matching_neighbours, 2, "min-matching-neighbours",
          "a tile's winning pixel needs this many neighbours to support it at its offset: its own "
          "above t_NCC, the others above --sweep.support-ncc (fewer where fewer see the pixel, "
          "unless --sweep.strict-support; 1 = the paper's rule)",
          InRange(0, 64))
// Also where the other neighbours do not see the pixel: on the noisy street, points one
// neighbour matched where the other did not see are far more often outliers
// (docs/design/accuracy.md "Winners that move the surface").
MS_OPTION(bool, strict_support, true, "strict-support",
          "a neighbour that does not see a pixel counts as not supporting it, so "
          "min-matching-neighbours binds everywhere (on by default; =false: where fewer "
          "neighbours see the pixel, all of those)",
          AnyValue())
// The unswept mesh (k = 0) is where the surface already is. If it competes, from the second
// iteration on nearly every tile winner of the pyramids is at k = 0, at an earlier winner's
// pixel, and goes as a duplicate or conflict: the loop stalls. With this, k = 0 competes for
// nothing and a pixel competes at k != 0 only where it matches the neighbour better than the
// unswept mesh does there (docs/design/accuracy.md "Winners that move the surface").
MS_OPTION(bool, winners_must_move, true, "winners-must-move",
          "tile winners only at offsets k != 0 that match better than the unswept mesh (k = 0) "
          "at their pixel (on by default; =false: the paper's rule, k = 0 competes like any "
          "offset)",
          AnyValue())
// Another neighbour supports a winning pixel when its NCC there is above this: a false match
// in repeated texture is at the wrong depth for the other neighbour, a true one only
// foreshortened.
MS_OPTION(double, support_ncc, 0.8, "support-ncc",
          "NCC above which another neighbour supports a winning pixel (min-matching-neighbours)",
          InRange(-1, 1))
MS_OPTION(double, gaussian_sigma_px, 8, "gaussian-sigma-px",
          "sigma of the NCC's Gaussian window (swept-resolution pixels)", InRange(0.5, 100))
// The image is split into round(W/size) x round(H/size) tiles (at least 1 x 1).
MS_OPTION(int, tile_size_px, 100, "tile-size-px",
          "tile size (swept-resolution pixels); one point per tile at most", AtLeast(1))
// Tiles counted per image instead, the same at any swept resolution: the longer side has this
// many. 16 stalls the upward pyramid's sweep with noisy images (docs/design/accuracy.md "What
// does not work"), so it is not the default.
MS_OPTION(int, tiles_across, 0, "tiles-across",
          "tiles along the image's longer side, overriding tile-size-px (0 = use tile-size-px)",
          InRange(0, 4096))
// Images are gray in [0, 1]; 1e-4 is a standard deviation of 2.55/255.
MS_OPTION(double, min_texture_variance, 1e-4, "min-texture-variance",
          "textureless below this weighted variance (gray in [0, 1])", AtLeast(0))
// The window is cut by the mesh's silhouette, the images' borders and occlusion.
MS_OPTION(double, min_window_weight, 0.5, "min-window-weight",
          "fraction of the Gaussian window that must be valid", InRangeOpenLow(0, 1))
// A point is visible in a neighbour if its depth is at most the shadow map's times (1 + this).
MS_OPTION(double, occlusion_tolerance, 0.01, "occlusion-tolerance",
          "relative depth tolerance of the neighbours' shadow maps", AtLeast(0))
// Noisy images are smoothed (one Gaussian for the job's images) until Immerkaer's estimate of
// their noise is about this; at 0.5 photographs as the real sets' stay as they are
// (sweep/image_noise.h, docs/design/sweep.md "Noisy images").
MS_OPTION(double, image_noise_target, 0.5, "image-noise-target",
          "smooth noisier images to about this noise before matching (grey levels of 255; 0 = "
          "never smooth)",
          AtLeast(0))
// Images larger than this (longest side) are swept at a pyramid level, halving until they fit
// (3072x2048 -> 1536x1024).
MS_OPTION(int, max_image_dimension, 1600, "max-image-dimension",
          "halve images until their longest side fits (0 = full size)", AtLeast(0))
// -1 = choose from max_image_dimension; L = images and intrinsics scaled by 2^-L.
MS_OPTION(int, pyramid_level, -1, "pyramid-level",
          "sweep at this pyramid level (-1 = from max-image-dimension, 0 = full size)",
          InRange(-1, 12))
