// Moving the vertices of a mesh without breaking it (docs/design/refine.md "Keeping the manifold"):
// the thin-plate regulariser's gradient, and moves that are halved or refused where they would
// make the mesh self-intersect, bring two faces (or two vertices) within the floating-point
// tolerance, or turn a face too far. The faces are never changed, so a closed 2-manifold stays
// one; with the checks, it also stays free of self-intersections, exactly and in double
// precision (the tolerance test is stricter than either).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "mesh/float_robustness.h"
#include "mesh/mesh.h"

namespace ms {

// The cross product of face f's edges over the points p: twice its area along its normal. Also
// for faces that are not (yet) in a mesh.
inline Eigen::Vector3d FaceCross(const std::vector<Eigen::Vector3d>& p,
                                 const std::array<int32_t, 3>& f) {
  return (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]);
}

// Neighbours of every vertex along the faces' edges (sorted, unique).
std::vector<std::vector<int32_t>> VertexNeighbours(const Mesh& mesh);

// Gradient of the thin-plate energy E = 1/2 sum_v |L(v)|^2, L(v) = mean of v's neighbours - v
// (the umbrella operator): dE/dv = -L(v) + sum over neighbours u of L(u) / deg(u).
std::vector<Eigen::Vector3d> ThinPlateGradient(const Mesh& mesh,
                                               const std::vector<std::vector<int32_t>>& neighbours);

// Moves that open a fold (--refine.unfold): every vertex flagged in `stuck` moves `fraction` of
// the way to its neighbours' mean, which flattens its ring; the others stay.
std::vector<Eigen::Vector3d> UnfoldingMoves(const Mesh& mesh,
                                            const std::vector<std::vector<int32_t>>& neighbours,
                                            const std::vector<uint8_t>& stuck, double fraction);

// What the checker (mesh/mesh_checker.h) objects to, looking at pairs with a face flagged in
// `focus` (empty: all; MeshCheckOptions::focus_faces) with `tolerance` as its absolute float
// tolerance: face pairs that intersect exactly (adjacent ones included: a fold), come within the
// tolerance or intersect in double precision (sharing no vertex); degenerate faces; vertex pairs
// within the tolerance. Moves and splits (refine/remesh.h) are undone on what it lists.
struct CheckerProblems {
  std::vector<std::array<int64_t, 2>> face_pairs;
  std::vector<int64_t> degenerate_faces;
  std::vector<std::array<int32_t, 2>> vertex_pairs;
  bool Empty() const {
    return face_pairs.empty() && degenerate_faces.empty() && vertex_pairs.empty();
  }
};
// `candidates` (optional): the pairs to look among instead of a search (mesh/float_robustness.h
// FindPairCandidates).
CheckerProblems FindCheckerProblems(const Mesh& mesh, double tolerance,
                                    const std::vector<uint8_t>& focus,
                                    const PairCandidates* candidates = nullptr);

struct MoveOptions {
  double tolerance = 0;           // absolute: faces sharing no vertex stay farther apart than this
  double max_face_turn_deg = 60;  // a face's normal turns by at most this
  int max_halvings = 4;           // a refused move is halved this many times, then dropped
  // Points the surface keeps clear of (the cameras' centres): a move that brings a face nearer
  // to one than `clearance` (and nearer than before) or across it is refused like the others.
  std::vector<Eigen::Vector3d> keep_clear;
  double clearance = 0;
};

struct MoveStats {
  int64_t moved = 0;    // vertices that moved (by their full or a halved displacement)
  int64_t halved = 0;   // of those, moved by less than asked
  int64_t refused = 0;  // vertices that did not move though asked to
  int rounds = 0;       // checks of the whole mesh
  double largest = 0;   // largest move made (mesh units)
};

// Adds displacement[v] to every vertex, halving it (then dropping it) for the vertices of
// faces that a check (the checker's, the face turn, the clearance) finds in trouble after the move,
// and checking again until no trouble involves a moved vertex. Trouble the mesh had before (between
// vertices that do not move) is left alone.
// `refused` (optional) gets 1 for every vertex asked to move that did not.
MoveStats MoveVerticesSafely(Mesh* mesh, const std::vector<Eigen::Vector3d>& displacement,
                             const MoveOptions& options, std::vector<uint8_t>* refused = nullptr);

}  // namespace ms
