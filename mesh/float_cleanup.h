// Makes a closed 2-manifold robust in floating point (mesh/float_robustness.h) with local
// operations that keep it a closed 2-manifold:
// - edge collapses for what is really close: vertices nearer than the tolerance, needles and
//   folds that bring two faces sharing no vertex within it. The removed vertex goes to the kept
//   one's position (no new positions: every vertex stays an input or swept point). A collapse
//   happens only under the link condition, without flipping a face or making a needle, without
//   bringing two faces near enough to cross, and only when it leaves fewer pairs of faces
//   within the tolerance (or crossing in Open3D's test) than it removes;
// - edge splits at the midpoint for what only Open3D's test sees: a face far larger than a
//   nearby small one makes Möller's plane distances (relative to the pair's extent) snap to 0,
//   and the pair "intersects" though it is farther apart than the tolerance. A split leaves the
//   surface where it was and shrinks the large face;
// - moves, where two faces sharing no vertex lie within the tolerance and no edge around them
//   may collapse (both sheets of a thin wall, with edges far longer than the gap): the corners
//   of one face, or one corner, go 2 tolerances (2e-6 of the diagonal with the defaults) away
//   from the other face along its normal, under the same conditions as a collapse. The only
//   operation that moves a vertex off its input position: 2 tolerances a move, and a vertex
//   is moved again only in a later round, if a problem is left around it.
// It repeats check, then operations, until the check passes or nothing more can be done (after
// the first, each check covers only the faces the last round made); if it ends with no fewer
// problems than it started with, the mesh is left as it was.
//
//   std::vector<uint8_t> scaffold = ...;   // per vertex, e.g. Steiner points
//   FloatCleanupStats stats = CleanForFloatingPoint(&mesh, &scaffold);
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "mesh/float_robustness.h"
#include "mesh/mesh.h"

namespace ms {

struct FloatCleanupOptions {
  // What "clean" means: check-mesh's default tolerance (1e-6 of the diagonal) ...
  FloatRobustnessOptions check;
  // ... times this margin, so that a sub-mesh with a smaller diagonal (the surface proper) and
  // the rounding of a written file pass check-mesh too.
  double margin = 2.0;
  // Edges longer than this fraction of the diagonal are never collapsed (a bound on how far
  // the surface moves).
  double max_collapse_fraction = 1e-3;
  int max_rounds = 100;  // a crumpled cluster takes a round per collapse around it
  // After each round only the faces it made are checked, against the whole mesh, and the
  // problems it left alone are carried over: the same lists as a whole-mesh check, in a
  // fraction of the time on a large mesh. true: each round is checked both ways, and a
  // difference stops the program (for tests).
  bool verify_rechecks = false;
};

struct FloatCleanupStats {
  int64_t problems_before = 0;  // near vertex pairs + close face pairs + double intersections
  int64_t problems_after = 0;
  int64_t collapses = 0;
  int64_t splits = 0;
  int64_t moves = 0;  // vertices, or a face's corners, moved 2 tolerances apart
  int rounds = 0;
  double tolerance = 0;  // absolute, as cleaned to
  double seconds = 0;
};

// `mesh` must be a closed 2-manifold (every edge in two faces, consistently oriented).
// `scaffold`, when given, holds one flag per vertex (1: scaffolding such as a Steiner point,
// whose faces are not the surface proper). A collapse keeps a non-scaffold vertex over a
// scaffold one; a split vertex is scaffold when either end of its edge is. The mesh is
// compacted (unreferenced vertices removed) and `scaffold` renumbered with it. `original`,
// when given, makes *mesh again as it was (a run extracts it from its manifold again): a
// cleanup that fails restores the mesh from it instead of from a copy of its own, which would
// come at the coordinator's peak of memory.
FloatCleanupStats CleanForFloatingPoint(Mesh* mesh, std::vector<uint8_t>* scaffold = nullptr,
                                        const FloatCleanupOptions& options = {},
                                        const std::function<Mesh()>& original = nullptr);

}  // namespace ms
