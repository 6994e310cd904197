// The options of the manifold reconstruction (paper sections 2.1 and 2.3, docs/design/manifold.md),
// one line each: MS_OPTION(type, name, default, flag, help, bound). Included by
// manifold/manifold_options.h only (no include guard on purpose).

// Ray tracing: every cell crossed by a camera->point segment gets w1, and its face neighbours
// get w2 (per crossing). A cell is free space when its weight reaches t_w. Paper: 4.0, 0.5, 4.0.
MS_OPTION(double, w1, 4.0, "w1", "w_1: weight a viewing ray adds to each cell it crosses", Above(0))
MS_OPTION(double, w2, 0.5, "w2", "w_2: weight added to each face neighbour of a crossed cell",
          AtLeast(0))
MS_OPTION(double, free_threshold, 4.0, "free-threshold",
          "t_w: a cell is free space when its weight reaches this", Above(0))
// Evidence of matter, beyond the paper (Labatut et al.'s graph cut weighs it too): a ray that
// ends at a point says the space just past the point is matter. Long cells that reach from a
// facade's last points past its edge are crossed by rays that graze the edge; without this one
// such ray frees them and the strip of facade up to the edge with them
// (docs/design/accuracy.md, "Where the carved band comes from").
MS_OPTION(double, behind_ratio, 0.0, "behind-ratio",
          "a cell stays matter while fewer rays cross it than this x the rays that, continued "
          "past their point (a vertex of the cell), enter it (0 = the paper's weights alone)",
          AtLeast(0))
// Which cells are free space: the paper's threshold on each cell's weight, or a minimum s-t cut
// of the cell graph (Labatut et al. 2009, as OpenMVS's ReconstructMesh): a ray's crossings of
// faces cost cutting there, cameras' cells are free, the cell past each point is matter, and
// every face costs cut-quality x (1 - the cosine of its worse circumsphere angle), so the surface
// prefers faces with large empty balls on both sides. Incremental insertion cuts again after
// each batch (docs/design/manifold.md, "The free-space cut").
MS_OPTION(FreeSpaceRule, visibility, FreeSpaceRule::kThreshold, "visibility",
          "which cells are free space: threshold (a cell's ray weight reaches t_w: the paper) or "
          "cut (a minimum cut of the cell graph weighing rays, the cells past the points and the "
          "faces' shapes; Labatut et al.)",
          AnyValue())
MS_OPTION(double, cut_quality, 1.0, "cut-quality",
          "with --manifold.visibility cut: the weight of a face's shape against one ray's",
          AtLeast(0))
MS_OPTION(double, cut_thickness, 1.0, "cut-thickness",
          "with --manifold.visibility cut: a ray costs less to cut within this x the median "
          "edge length of its point (the points' noise)",
          AtLeast(0))
MS_OPTION(W2Rule, w2_rule, W2Rule::kCameraSide, "w2-rule",
          "which face neighbours of a crossed cell get w_2: camera-side (only between the camera "
          "and the cell) or all-faces (the paper's wording)",
          AnyValue())
// Steiner points (manifold/steiner_points.h): a grid on the faces of the bounding box of points
// and cameras, enlarged by steiner_margin x its diagonal, so flat or tiny inputs still
// triangulate in 3D and every camera lies inside.
MS_OPTION(double, steiner_margin, 0.5, "steiner-margin",
          "Steiner box: bounding box of points and cameras enlarged by this x its diagonal",
          Above(0))
MS_OPTION(int, steiner_grid, 3, "steiner-grid",
          "Steiner points per edge of the box (2 = corners only)", InRange(2, 64))
// Graded Steiner points in the empty space (an octree whose cells grow with the distance to the
// points). on: all of them, a cell of Steiner points only being free space (viewing rays cross
// 3x fewer cells at 10^6 points); hidden: only those behind what every view holding them sees
// (inside objects, under the ground: they keep long cells from joining a facade to the far box
// points, which rays then carve through) and those in open air that rays cross densely
// (manifold/steiner_sight.h), the default at every size; off: the paper's box grid only
// (docs/design/manifold.md compares them).
MS_OPTION(GradedSteiner, steiner_graded, GradedSteiner::kHidden, "graded-steiner",
          "graded Steiner points in the empty space: hidden (those behind what every camera "
          "sees, and in open air far from the points), on (all, cells of Steiner points only "
          "being free) or off (the paper's box grid only); docs/design/manifold.md",
          AnyValue())
MS_OPTION(double, steiner_clearance, 1.5, "steiner-clearance",
          "graded Steiner points keep this x their size away from every point", AtLeast(1))
MS_OPTION(double, steiner_min_spacing, 6.0, "steiner-min-spacing",
          "smallest graded Steiner cell, in median point spacings", Above(0))
// Near-duplicate points (manifold/point_merging.h). Two input points closer than merge_pixels
// of a pixel's footprint at their depth in the cameras that see them, or than merge_floor x the
// Steiner box's diagonal, are one point (their visibility united). A new (swept) point nearer a
// vertex than merge_new_pixels of a footprint, or than the same floor, is a duplicate whose
// cameras the vertex gains. The floor is twice the
// checker's default float tolerance (1e-6 of a mesh's diagonal, and every mesh lies in the box), so
// no merged pair is one the checker flags. Without merging, SfM tracks triangulated 1e-8 apart and
// swept points on top of vertices make faces that floating-point tools see as self-intersecting
// (docs/design/manifold.md).
MS_OPTION(double, merge_pixels, 0.5, "merge-pixels",
          "input points closer than this fraction of a pixel's footprint at their depth are one "
          "point",
          AtLeast(0))
MS_OPTION(double, merge_floor, 2e-6, "merge-floor",
          "...and points closer than this fraction of the Steiner box's diagonal (input and new)",
          AtLeast(0))
// 0 by default: the sweep refines depth below a pixel on purpose.
MS_OPTION(double, merge_new_pixels, 0.0, "merge-new-pixels",
          "a new (swept) point closer to a vertex than this fraction of a pixel's footprint (or "
          "the floor) is a duplicate: the vertex gains its cameras",
          AtLeast(0))
// Written meshes (manifold/output_meshes.h): needles, folds and size jumps that floating-point
// tools see as self-intersections are removed by edge collapses and splits that keep the mesh a
// closed 2-manifold (mesh/float_cleanup.h). The triangulation itself is not changed.
MS_OPTION(bool, float_cleanup, true, "float-cleanup",
          "make written meshes robust in floating point (Open3D, MeshLab): collapse and split "
          "edges until check-mesh's float report passes",
          AnyValue())
// How a batch of swept points joins: point by point with the paper's conflict rule, or a
// rebuild from every point so far. On the pyramids many points the conflict rule discards are
// the surface's (a Steiner point's disc of O cannot shrink); docs/design/accuracy.md measures both.
MS_OPTION(InsertionMode, insertion, InsertionMode::kIncremental, "insertion",
          "how swept points join: incremental (point by point, discarding a point whose conflict "
          "region cannot leave O: the paper) or rebuild (triangulation, rays and O again from "
          "every point so far after each batch; holds the points)",
          AnyValue())
// Incremental insertion: E, the cells shrunk out of O before inserting a point, is the conflict
// region D plus its face neighbours (0), every cell sharing a vertex with D (1), or the face
// neighbours first and, only if D still meets O, the stars of D's vertices that are points, not
// Steiner points (2; docs/design/accuracy.md "What does not work").
MS_OPTION(int, shrink_neighbourhood, 0, "shrink-neighbourhood",
          "cells shrunk before an insertion: 0 = conflict region + face neighbours, 1 = + every "
          "cell sharing a vertex, 2 = 0, then the stars of its points (not Steiner points) "
          "where 0 is not enough",
          InRange(0, 2))
// Regrowing after an insertion batch: from every free cell on the boundary of O (the paper) or
// only from those with a vertex the batch touched (docs/design/manifold.md compares them).
MS_OPTION(RegrowSeeds, regrow_seeds, RegrowSeeds::kBoundary, "regrow-seeds",
          "where regrowing starts after an insertion batch: boundary (every free cell on the "
          "boundary of O, the paper) or changed (only cells with a vertex the batch touched)",
          AnyValue())
// Growing adds one cell at a time; a pocket of free space that touches O only where any single
// cell would pinch the surface joins whole, or a surface vertex's free cells at a time
// (docs/design/manifold.md, "Pockets of free space").
MS_OPTION(bool, join_pockets, true, "join-pockets",
          "after growing, join pockets of free space that growing cannot enter one cell at a time",
          AnyValue())
// After an insertion, a free pocket that cannot join alone (a vertex would not stay regular)
// joins with the matter pieces (of at most 16 cells) that pinch its vertices, found again for up
// to this many rounds: a point swept a few centimetres into free space can leave a fin of free
// cells out of O, from the scene's edge to a box point in front of a camera
// (docs/design/accuracy.md, "Fins in front of the cameras").
MS_OPTION(int, pocket_pinch_rounds, 2, "pocket-pinch-rounds",
          "after an insertion, rounds of pinching matter pieces joined with a free pocket that "
          "cannot join O alone (0 = the pocket alone)",
          InRange(0, 8))
// Optionally a swept point gets the rays of every camera that sees it through the iteration's
// mesh, not only of the cameras that matched it (coordinator/witness_cameras.h). A face nearer
// the point than this share of the camera's distance to it does not hide it. Off by default:
// on the street those rays carve the corners of nearer buildings away (docs/design/accuracy.md,
// "Witness rays").
MS_OPTION(double, witness_tolerance, 0, "witness-tolerance",
          "rays from every camera that sees a swept point through the mesh, not only the "
          "matching ones: faces within this share of the camera's distance of the point do not "
          "hide it (0 = the matching cameras' rays only, the paper; 0.01 helps the pyramids and "
          "hurts streets)",
          InRange(0, 0.5))
MS_OPTION(bool, grow_all_components, false, "grow-all-components",
          "grow every free-space component, not only the heaviest cell's", AnyValue())
// Debugging: the full validity check after every step (slow).
MS_OPTION(bool, validate_each_step, false, "validate",
          "check the whole state (labels, weights, manifold) after every step (slow)", AnyValue())
