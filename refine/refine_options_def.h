// The options of photometric refinement (docs/design/refine.md), one line each:
//   MS_OPTION(type, name, default, flag, help, bound)
// Expanded by base/option_group_members.h in refine/refine_options.h (no include guard).

// Coarse to fine: `levels` image scales, each half the size of the next, the finest being the
// images halved until they fit max_image_dimension (0: full size; 1600 as the sweep's default).
// Iterations are split evenly over the levels, the finest taking what is left over. The coarse
// levels cost little and move the surface furthest (docs/design/refine.md "Coarse to fine"
// measures the level count).
MS_OPTION(int, iterations, 40, "iterations", "gradient steps in all, over all levels",
          InRange(0, 100000))
MS_OPTION(int, levels, 4, "levels", "image scales, coarse to fine (each half the next)",
          InRange(1, 8))
MS_OPTION(int, max_image_dimension, 1600, "max-image-dimension",
          "finest scale: images halved until their longest side fits this (0: full size)",
          AtLeast(0))
// The similarity: ZNCC over a Gaussian window, per pixel of the reference camera. A wide window
// averages the photographs' noise and reaches across the swept mesh's facets; the sweep's 8 px
// is about as good (docs/design/refine.md "The window").
MS_OPTION(double, gaussian_sigma_px, 6.0, "gaussian-sigma-px",
          "sigma of the ZNCC's Gaussian window (pixels of the level)", InRange(0.5, 50))
// Images are gray in [0, 1]; 1e-4 is a standard deviation of 2.55/255 (as the sweep).
MS_OPTION(double, min_texture_variance, 1e-4, "min-texture-variance",
          "pixels whose weighted variance is below this (either image) are left out", AtLeast(0))
// A reprojected pixel counts only if the point is the nearest surface in the neighbour too:
// its camera z at most (1 + this) x the neighbour's depth map there.
MS_OPTION(double, occlusion_tolerance, 0.01, "occlusion-tolerance",
          "relative depth tolerance of the visibility test in the neighbour", Above(0))
// The step (docs/design/refine.md "Step"): a vertex moves by -step x g / H, where g is the energy's
// gradient and H the squared parallax rate of its pixels (a Gauss-Newton scale: one unit of
// `step` moves a vertex by about one pixel of reprojection shift per unit of normalised
// gradient), and never by more than max_step_px pixels of reprojection shift.
MS_OPTION(double, step, 0.5, "step", "gradient step (pixels of reprojection shift)", Above(0))
MS_OPTION(double, max_step_px, 0.5, "max-step-px",
          "largest move of a vertex per iteration, in pixels of reprojection shift", Above(0))
// Thin plate (umbrella operator): E_s = 1/2 sum_v |L(v)|^2, L(v) = mean of neighbours - v; a
// vertex also moves by -smoothness x dE_s/dv (stable below 1/8 in explicit steps).
MS_OPTION(double, smoothness, 0.002, "smoothness",
          "thin-plate weight: vertices move by this x the bi-Laplacian per iteration",
          InRange(0, 0.125))
// A vertex whose move was refused (it sits in a fold the images push it into) moves, in the next
// iteration, this fraction of the way to its neighbours' mean instead, at most max_step_px
// (0: it keeps trying; docs/design/refine.md "Unfolding").
MS_OPTION(double, unfold, 0.5, "unfold",
          "a vertex whose move was refused moves this fraction towards its neighbours' mean "
          "at the next iteration (0: off)",
          InRange(0, 1))
// Pixels where the ray meets the face at a grazing angle give unstable depth derivatives.
MS_OPTION(double, min_cos_incidence, 0.1, "min-cos-incidence",
          "pixels whose ray meets its face with |cos| below this are left out", InRange(0, 1))
// A move that would make the mesh self-intersect, bring two faces within the float tolerance
// (check-mesh's, times the cleanup's margin) or turn a face by more than max_face_turn_deg is
// halved, up to this many times, then refused.
MS_OPTION(int, max_halvings, 4, "max-halvings", "halvings of a refused move before it is dropped",
          InRange(0, 30))
MS_OPTION(double, max_face_turn_deg, 60, "max-face-turn-deg",
          "a move may turn a face's normal by at most this many degrees", InRange(1, 179))
// Remeshing (refine/remesh.h): at the start of every level, edges longer than max_edge_px
// pixels of that level (in the camera that sees them finest) are split at their midpoints, so
// that detail finer than the starting mesh can appear; 0 turns it off. 16 by default: on the
// pyramids and fountain-P11 it beats no remeshing at about twice the refinement's time, and 8
// costs twice 16's time for no more (docs/design/refine.md "Remeshing").
MS_OPTION(double, max_edge_px, 16, "max-edge-px",
          "split edges longer than this many pixels of the level (0: no remeshing)", AtLeast(0))
// With remeshing, first: edges shorter than min_edge_px pixels of the level are collapsed to
// their midpoints (where that keeps the mesh a valid closed 2-manifold); 0: no collapses.
// Below max_edge_px / 2, so that the halves of a split edge are not collapsed again.
MS_OPTION(double, min_edge_px, 2, "min-edge-px",
          "with remeshing, collapse edges shorter than this many pixels of the level (0: none)",
          AtLeast(0))
MS_OPTION(int64_t, max_vertices, 2000000, "max-vertices",
          "remeshing adds no vertex beyond this many", AtLeast(1))
// With remeshing, after the splits of a level: edges whose two faces' normals are within this
// angle are flipped where that rounds the faces (refine/remesh.h FlipEdges); 0: no flips.
MS_OPTION(double, flip_dihedral_deg, 10, "flip-dihedral-deg",
          "with remeshing, flip edges of face pairs this flat (degrees; 0: no flips)",
          InRange(0, 90))
// The pairs' gradients (refine/gradient_kernel.h): auto (GLSL on a GPU, else the fast CPU
// kernel), glsl, cpu, or the exact double-precision reference (slow; for checks). Travels with
// the jobs; "auto" is resolved by each worker, so name one for identical bytes across a cluster
// whose machines differ.
MS_OPTION(std::string, kernel, "auto", "kernel",
          "gradient kernel: auto (glsl on a GPU, else cpu), glsl, cpu, reference", AnyValue())
MS_OPTION(int, threads, 0, "threads", "threads for the camera pairs (0: one per core)", AtLeast(0))
