// The independent manifold checker: reads only a Mesh (what a file holds), never the builder's
// data structures, so tests of the builder cannot share its bugs. See
// docs/reference/mesh-checker.md.
//
// A vertex is regular (the paper's Fig. 1, after Litvinov & Lhuillier) when the edges opposite
// to it form one closed path without loops; with boundaries allowed, one open path is also
// accepted. Every count below is exact (CGAL exact predicates for zero area and intersections),
// except the floating-point robustness report (mesh/float_robustness.h), which says what tools
// working in double precision will see.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "mesh/float_robustness.h"
#include "mesh/mesh.h"

namespace ms {

struct MeshCheckOptions {
  bool allow_boundary = false;              // valid = manifold with boundary (open fans allowed)
  bool check_self_intersections = true;     // every face-pair test, exact and floating-point
  int max_examples = 10;                    // indices listed per kind of problem in the report
  int64_t max_self_intersections = 100000;  // stop each pair search after this many pairs
  // Floating-point robustness (mesh/float_robustness.h): vertices or faces sharing no vertex
  // closer than the tolerance, and face pairs that intersect in double precision, make the
  // mesh not valid unless allow_float_issues.
  double float_tolerance = 1e-6;    // --float-tolerance: relative to the bounding-box diagonal
  double float_tolerance_abs = 0;   // --float-tolerance-abs: > 0 replaces it (mesh units)
  bool allow_float_issues = false;  // --allow-float-issues: reported, but valid regardless
  // Empty: every face pair. Otherwise one flag per face: the pair searches (exact and float)
  // test only pairs with a flagged face (FloatRobustnessOptions::focus_faces); the counts are
  // then those of the flagged faces only, not a verdict on the mesh.
  std::vector<uint8_t> focus_faces;
  // Set: the pair searches take their pairs from this list (FloatRobustnessOptions::candidates).
  const PairCandidates* candidates = nullptr;
  // False: only the geometry (invalid and degenerate faces, self-intersections, floating-point
  // robustness); edges, vertex links and components are not looked at, and the report's
  // verdicts say nothing. For callers that change vertices only, whose topology is known.
  bool check_topology = true;
  void Check() const;  // throws InputError naming the field
};

// One connected component: faces that share vertices, directly or through other faces.
struct MeshComponent {
  int64_t num_vertices = 0;  // referenced by its non-degenerate faces
  int64_t num_edges = 0;
  int64_t num_faces = 0;             // faces with three distinct indices
  int64_t euler_characteristic = 0;  // V - E + F
  bool closed = false;               // no boundary edge
  bool manifold = false;         // no non-manifold edge or vertex, no face with a repeated index
  bool oriented = false;         // every two-face edge traversed once in each direction
  bool orientable = false;       // faces could be flipped to make it oriented
  std::optional<int64_t> genus;  // (2 - chi) / 2 when closed, manifold and orientable
  std::optional<double> signed_volume;  // when closed, manifold and oriented; > 0: outward
};

struct MeshReport {
  // Options the report was made with.
  bool allow_boundary = false;
  bool self_intersections_checked = false;
  bool allow_float_issues = false;

  int64_t num_vertices = 0;
  int64_t num_faces = 0;
  int64_t num_edges = 0;                      // distinct undirected edges of non-degenerate faces
  int64_t num_invalid_faces = 0;              // index out of range or a non-finite vertex
  int64_t num_boundary_edges = 0;             // edges in exactly one face
  int64_t num_non_manifold_edges = 0;         // edges in three or more faces
  int64_t num_boundary_vertices = 0;          // regular but open fan (one path): on a boundary
  int64_t num_non_manifold_vertices = 0;      // opposite edges are not one cycle or one path
  int64_t num_inconsistent_edges = 0;         // two-face edges traversed twice the same way
  int64_t num_degenerate_faces = 0;           // repeated index or zero area (exact)
  int64_t num_duplicate_faces = 0;            // same vertex set as an earlier face
  int64_t num_unreferenced_vertices = 0;      // in no face
  int64_t num_self_intersections = 0;         // face pairs that meet other than at shared elements
  bool self_intersections_truncated = false;  // stopped at max_self_intersections
  int64_t num_components = 0;
  int64_t euler_characteristic = 0;       // sum over components
  std::optional<int64_t> genus;           // sum over components, when every one has a genus
  std::vector<MeshComponent> components;  // largest first

  // The first few (by index) of each problem.
  std::vector<std::array<int32_t, 2>> boundary_edge_examples;
  std::vector<std::array<int32_t, 2>> non_manifold_edge_examples;
  std::vector<std::array<int32_t, 2>> inconsistent_edge_examples;
  std::vector<int32_t> non_manifold_vertex_examples;
  std::vector<int32_t> unreferenced_vertex_examples;
  std::vector<int64_t> invalid_face_examples;
  std::vector<int64_t> degenerate_face_examples;
  std::vector<int64_t> duplicate_face_examples;
  std::vector<std::array<int64_t, 2>> self_intersection_examples;

  // What double-precision tools see: shortest edge, smallest angle, near-coincident vertices,
  // close face pairs and double-precision intersections (face pairs only when
  // self_intersections_checked).
  FloatRobustnessReport float_robustness;

  // Closed 2-manifold: at least one face, no boundary, no non-manifold edge or vertex,
  // consistently oriented, no invalid/degenerate/duplicate face, no self-intersection (when
  // checked). Unreferenced vertices are reported but allowed. Exact: floating-point robustness
  // plays no part here.
  bool is_closed_manifold = false;
  // float_robustness found no near-coincident vertices, close face pairs or double-precision
  // intersections.
  bool is_float_robust = false;
  // is_closed_manifold, or with allow_boundary the same except that boundaries are allowed;
  // and is_float_robust unless allow_float_issues.
  bool is_valid = false;

  // One line per reason why the mesh is not valid (empty when valid).
  std::vector<std::string> Problems() const;
  // Human-readable table, and the same as JSON (an object; `source` names the input).
  std::string ToTable(const std::string& source = "") const;
  std::string ToJson(const std::string& source = "") const;
};

MeshReport CheckMesh(const Mesh& mesh, const MeshCheckOptions& options = {});

}  // namespace ms
