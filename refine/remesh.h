// Remeshing during refinement (docs/design/refine.md "Remeshing"): edges longer than the image
// resolution asks for are split at their midpoints, so detail finer than the starting mesh can
// appear; edges shorter than it resolves are collapsed; edges of nearly flat face pairs are
// flipped where that rounds the faces. A split replaces
// the two faces of an edge by four, so a closed 2-manifold stays one. The new vertex is the edge's
// midpoint moved 8 tolerances off it along the faces' mean normal: exactly on the edge, chains of
// splits along a crease leave collinear vertices whose faces double-precision tests (Open3D's among
// them) find touching. Each pass of splits is checked as moves are (exact self-intersections, the
// floating-point tolerance), and the splits whose faces the checker objects to are undone and not
// tried again.
//
// Every step takes `frozen` vertex flags (one per vertex of the mesh it is given, or empty for
// none; vertices added later are free): a split, collapse or flip with a frozen end is not made,
// so the faces whose three vertices are all frozen stay as they are.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "mesh/mesh.h"

namespace ms {

struct SplitStats {
  int64_t splits = 0;   // edges split (vertices added)
  int64_t refused = 0;  // splits undone because the checker objected
  int rounds = 0;       // passes over the edges
};

// Splits every edge longer than max_length(midpoint), longest first, repeating over the new
// edges until none is too long (or all that are were refused), or the mesh has max_vertices
// vertices. Unreferenced vertices are removed at the end. `tolerance` is the absolute
// floating-point tolerance of the check (as MoveOptions::tolerance). Every edge must be in
// two faces, or one on a boundary.
SplitStats SplitLongEdges(Mesh* mesh,
                          const std::function<double(const Eigen::Vector3d&)>& max_length,
                          int64_t max_vertices, double tolerance,
                          const std::vector<uint8_t>& frozen = {});

struct CollapseStats {
  int64_t collapses = 0;  // edges collapsed (vertices removed)
  int64_t refused = 0;    // collapses undone because the checker objected
  int rounds = 0;         // passes over the edges
};

// Collapses edges shorter than min_length(midpoint), shortest first, each to its midpoint, so
// that the mesh does not keep more vertices than the images resolve. A collapse removes the
// edge's two faces and one vertex; it is made only where it keeps a closed 2-manifold one (the
// link condition: the edge's ends share exactly the two opposite vertices as neighbours; the
// opposite vertices keep at least 3 neighbours; more than 4 vertices remain) and turns no
// remaining face by more than max_face_turn_deg (nor flips one); collapses touching one another
// wait for the next pass. Each pass is checked as splits are, and the collapses whose faces the
// checker objects to are left out and not tried again. Unreferenced vertices are removed at
// the end. Every edge must be in exactly two faces.
CollapseStats CollapseShortEdges(Mesh* mesh,
                                 const std::function<double(const Eigen::Vector3d&)>& min_length,
                                 double max_face_turn_deg, double tolerance,
                                 const std::vector<uint8_t>& frozen = {}, int max_rounds = 5);

struct FlipStats {
  int64_t flips = 0;    // edges flipped
  int64_t refused = 0;  // flips undone because the checker objected
  int rounds = 0;       // passes over the edges
};

// Flips edges whose two faces are nearly coplanar (normals within max_dihedral_deg) and whose
// opposite angles sum to more than pi (the Delaunay criterion on the pair: the flip makes the
// smallest angle of the two faces larger), so that the long, thin faces splitting and moving
// leave become rounder without changing the surface by more than that angle allows. A flip
// keeps the face count and a closed 2-manifold one: it is skipped where the new edge exists
// already or a vertex would keep fewer than 3 neighbours; flips are checked as splits are and
// undone where the checker objects. Passes repeat until none flips (at most max_rounds).
FlipStats FlipEdges(Mesh* mesh, double max_dihedral_deg, double tolerance,
                    const std::vector<uint8_t>& frozen = {}, int max_rounds = 5);

}  // namespace ms
