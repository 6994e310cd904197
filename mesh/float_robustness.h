// Floating-point robustness of a mesh: what tools that work in double precision (Open3D,
// MeshLab, game and physics engines) will see in it, next to the exact verdict of the checker
// (mesh/mesh_checker.h). A mesh can be a valid closed 2-manifold in exact arithmetic and still
// have two distinct vertices 1e-7 m apart, or needle faces whose neighbours cross them after
// rounding; such a mesh "self-intersects" in Open3D. See docs/reference/mesh-checker.md.
//
// Everything here is computed in double precision on purpose (no exact predicates).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "mesh/mesh.h"

namespace ms {

// Pairs that the checks of a mesh whose vertices move within known bounds can only ever find
// among (FindPairCandidates), sorted.
struct PairCandidates {
  std::vector<std::array<int32_t, 2>> faces;     // f < g, those sharing a vertex included
  std::vector<std::array<int32_t, 2>> vertices;  // u < v
};

struct FloatRobustnessOptions {
  // The distance below which two vertices, or two faces that share no vertex, count as
  // touching: relative_tolerance times the bounding-box diagonal of the referenced vertices,
  // or absolute_tolerance (mesh units) when that is > 0.
  double relative_tolerance = 1e-6;
  double absolute_tolerance = 0;
  bool check_face_pairs = true;  // close face pairs and double-precision intersections (slow)
  int max_examples = 10;         // indices listed per kind of problem
  int64_t max_pairs = 100000;    // each pair search stops after this many pairs
  // Empty: every pair is tested. Otherwise one flag per face: only face pairs with a flagged face,
  // and vertex pairs with a vertex of one, are tested (a partial check, for code that changed
  // those faces of a mesh that passed before, e.g. refine/mesh_moves.h; not a verdict on the mesh).
  // The shortest edge and smallest angle are then those of the flagged faces.
  std::vector<uint8_t> focus_faces;
  // The pair searches run slab by slab along x, with about this many boxes a slab: CGAL copies
  // the boxes it searches, and a slab's copy is all that is held. The pairs found do not depend
  // on it (nor their order, unless a search stops at max_pairs).
  int64_t boxes_per_slab = int64_t{1} << 18;
  // Called on the searching thread with every face pair (f < g) whose boxes, enlarged by the
  // tolerance, overlap (a superset of the pairs whose exact boxes do), those sharing a vertex
  // included, before the pair tests; a pair of two flagged faces may come twice. The exact
  // self-intersection test (mesh_checker.cc) shares the search this way. Not called for what
  // a search stopped at max_pairs did not reach (both *_truncated flags then set).
  std::function<void(int64_t f, int64_t g)> on_box_pair;
  // Set: no box search; the pairs of this list (with a flagged face, or a vertex of one) whose
  // boxes meet are the pairs a search would find, in list order. For callers that check one
  // mesh many times while its vertices move within known bounds (refine/mesh_moves.h).
  const PairCandidates* candidates = nullptr;
  void Check() const;  // throws InputError naming the field
};

struct FloatRobustnessReport {
  bool face_pairs_checked = false;
  double diagonal = 0;            // bounding-box diagonal of the vertices of usable faces
  double tolerance = 0;           // absolute (mesh units), as used
  double relative_tolerance = 0;  // as given, or tolerance / diagonal for an absolute one

  // Shortest edge of a face with three distinct indices, and the face it was seen in.
  std::optional<double> shortest_edge;
  std::array<int32_t, 2> shortest_edge_vertices{-1, -1};
  int64_t shortest_edge_face = -1;
  // Smallest interior angle (degrees) of a face with three distinct indices, at which corner.
  std::optional<double> smallest_angle_degrees;
  int64_t smallest_angle_face = -1;
  int32_t smallest_angle_vertex = -1;

  // Pairs of distinct vertices (of usable faces) at most `tolerance` apart.
  int64_t num_near_vertex_pairs = 0;
  bool near_vertex_pairs_truncated = false;
  std::optional<double> closest_vertex_distance;  // of the pairs found
  std::vector<std::array<int32_t, 2>> near_vertex_examples;

  // Pairs of faces sharing no vertex index whose distance is at most `tolerance` (0 when they
  // cross or touch in double precision).
  int64_t num_close_face_pairs = 0;
  bool close_face_pairs_truncated = false;
  std::optional<double> closest_face_pair_distance;  // of the pairs found
  std::vector<std::array<int64_t, 2>> close_face_pair_examples;

  // Pairs of faces sharing no vertex index that intersect by Möller's triangle-triangle test
  // in double precision, as Open3D's TriangleMesh::GetSelfIntersectingTriangles decides it.
  int64_t num_float_intersections = 0;
  bool float_intersections_truncated = false;
  std::vector<std::array<int64_t, 2>> float_intersection_examples;

  // No near vertices, no close face pairs, no double-precision intersections (the face-pair
  // counts only when they were checked).
  bool IsRobust() const {
    return num_near_vertex_pairs == 0 && num_close_face_pairs == 0 && num_float_intersections == 0;
  }
};

// The face pairs and vertex pairs whose boxes, grown by `tolerance` (absolute) and holding each
// vertex both where it is in `mesh` and at `to`, meet, with a face flagged in `focus` (empty: all)
// or a vertex of one. While every vertex stays between the two places (as before + s x (to -
// before) with s in [0, 1] does, rounding included), a check of the mesh with that tolerance
// and focus finds its pairs among these (FloatRobustnessOptions::candidates).
PairCandidates FindPairCandidates(const Mesh& mesh, const std::vector<Eigen::Vector3d>& to,
                                  double tolerance, const std::vector<uint8_t>& focus);

// The absolute tolerance a check would use (CheckFloatRobustness's report.tolerance), without
// the check: one pass over the usable faces' vertices.
double FloatCheckTolerance(const Mesh& mesh, const std::vector<uint8_t>& usable,
                           const FloatRobustnessOptions& options = {});

// Faces with usable[f] == 0 (an index out of range or a non-finite vertex) are ignored; the
// others, degenerate ones included, take part in the pair tests. Edges and angles are measured
// on faces with three distinct indices.
FloatRobustnessReport CheckFloatRobustness(const Mesh& mesh, const std::vector<uint8_t>& usable,
                                           const FloatRobustnessOptions& options = {});

// Whether x lies over triangle t: its projection along t's normal falls inside t or on its
// edges (false for a degenerate t).
bool PointOverTriangle(const Eigen::Vector3d& x, const std::array<Eigen::Vector3d, 3>& t);

// The point of triangle t nearest to x, in double precision (a degenerate t: the nearest point
// of its edges).
Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& x,
                                       const std::array<Eigen::Vector3d, 3>& t);

// The geometric kernels, exposed for tests.
namespace float_robustness_internal {

using Triangle = std::array<Eigen::Vector3d, 3>;

// Möller's test ("A fast triangle-triangle intersection test", JGT 1997, the division-free
// variant with plane distances below 1e-6 snapped to 0) after Open3D's preconditioning (the six
// points shifted to zero mean and scaled to unit spread per axis): true when the triangles
// intersect or touch. Bit for bit what Open3D's IntersectionTest::TriangleTriangle3d computes.
bool TrianglesIntersectLikeOpen3d(const Triangle& p, const Triangle& q);

// True when segment ab crosses triangle t (touching included), in double precision; false
// when ab lies in the triangle's plane (left to the distance computation).
bool SegmentCrossesTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Triangle& t);

// Distance between two triangles in double precision: 0 when an edge of one crosses the other
// (and meets it there: nearly coplanar edges that only seem to cross are measured), else the
// minimum of the 6 point-triangle and 9 segment-segment distances.
double TriangleDistance(const Triangle& p, const Triangle& q);

// True when triangles p and q are certainly more than `distance` apart: their projections onto
// one of eight axes (the two normals and each edge's normal within its triangle's plane) leave a
// gap wider than that, with a margin for rounding. A gap along any unit axis bounds the distance
// from below, so TriangleDistance, and the exact test where `distance` is 0, need not look at the
// pair; most pairs a box search hands over are a face or more apart like this. (Möller's test as
// Open3D runs it snaps relative to per-axis scales and can see such a pair touch: it is not
// spared.)
bool TrianglesSurelyApart(const Triangle& p, const Triangle& q, double distance);

// A point of p and a point of q at their smallest distance (the 6 point-triangle and 9
// segment-segment candidates; meaningless when they cross): the direction that parts them.
std::array<Eigen::Vector3d, 2> TriangleClosestPoints(const Triangle& p, const Triangle& q);

// The nearest float at or below x, and at or above it: a box of floats rounded outward holds the
// double box it stands for, so a search over such boxes finds a superset of the double boxes'
// pairs (half the memory; exact tests decide after it).
inline float FloatAtOrBelow(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity())
                                    : f;
}
inline float FloatAtOrAbove(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

}  // namespace float_robustness_internal

}  // namespace ms
