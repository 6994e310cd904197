#include "refine/mesh_moves.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <initializer_list>

#include "mesh/float_robustness.h"
#include "mesh/mesh_checker.h"

namespace ms {

std::vector<std::vector<int32_t>> VertexNeighbours(const Mesh& mesh) {
  std::vector<std::vector<int32_t>> neighbours(mesh.vertices.size());
  for (const auto& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      neighbours[f[k]].push_back(f[(k + 1) % 3]);
      neighbours[f[k]].push_back(f[(k + 2) % 3]);
    }
  }
  for (auto& n : neighbours) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return neighbours;
}

std::vector<Eigen::Vector3d> UnfoldingMoves(const Mesh& mesh,
                                            const std::vector<std::vector<int32_t>>& neighbours,
                                            const std::vector<uint8_t>& stuck, double fraction) {
  std::vector<Eigen::Vector3d> move(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (size_t v = 0; v < stuck.size() && v < move.size(); ++v) {
    if (!stuck[v] || neighbours[v].empty()) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int32_t u : neighbours[v]) mean += mesh.vertices[u];
    move[v] = fraction * (mean / static_cast<double>(neighbours[v].size()) - mesh.vertices[v]);
  }
  return move;
}

std::vector<Eigen::Vector3d> ThinPlateGradient(
    const Mesh& mesh, const std::vector<std::vector<int32_t>>& neighbours) {
  const size_t n = mesh.vertices.size();
  std::vector<Eigen::Vector3d> umbrella(n, Eigen::Vector3d::Zero());
  for (size_t v = 0; v < n; ++v) {
    if (neighbours[v].empty()) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int32_t u : neighbours[v]) mean += mesh.vertices[u];
    umbrella[v] = mean / static_cast<double>(neighbours[v].size()) - mesh.vertices[v];
  }
  std::vector<Eigen::Vector3d> gradient(n, Eigen::Vector3d::Zero());
  for (size_t v = 0; v < n; ++v) {
    if (neighbours[v].empty()) continue;
    Eigen::Vector3d g = -umbrella[v];
    for (int32_t u : neighbours[v]) {
      g += umbrella[u] / static_cast<double>(neighbours[u].size());
    }
    gradient[v] = g;
  }
  return gradient;
}

CheckerProblems FindCheckerProblems(const Mesh& mesh, double tolerance,
                                    const std::vector<uint8_t>& focus,
                                    const PairCandidates* candidates) {
  MeshCheckOptions check;
  check.focus_faces = focus;
  check.candidates = candidates;
  check.allow_boundary = true;
  check.float_tolerance_abs = tolerance;
  check.max_examples = INT_MAX;
  check.max_self_intersections = INT64_MAX;
  check.check_topology = false;  // moves and the remeshing's own steps keep it
  MeshReport report = CheckMesh(mesh, check);
  FloatRobustnessReport& f = report.float_robustness;
  CheckerProblems p;
  p.face_pairs = std::move(report.self_intersection_examples);
  for (const auto* pairs : {&f.close_face_pair_examples, &f.float_intersection_examples}) {
    p.face_pairs.insert(p.face_pairs.end(), pairs->begin(), pairs->end());
  }
  p.degenerate_faces = std::move(report.degenerate_face_examples);
  p.vertex_pairs = std::move(f.near_vertex_examples);
  return p;
}

namespace {

// Vertices of faces that the move from `before` to `mesh` turned too far (or flipped).
void MarkTurnedFaces(const Mesh& mesh, const std::vector<Eigen::Vector3d>& before,
                     const std::vector<uint8_t>& moving, double cos_limit,
                     std::vector<uint8_t>* trouble) {
  for (const auto& f : mesh.faces) {
    if (!moving[f[0]] && !moving[f[1]] && !moving[f[2]]) continue;
    const Eigen::Vector3d n0 = FaceCross(before, f), n1 = FaceCross(mesh.vertices, f);
    if (n0.dot(n1) <= cos_limit * n0.norm() * n1.norm()) {
      for (int32_t v : f) (*trouble)[v] = 1;
    }
  }
}

// Vertices of moved faces in `focus` that came nearer to a kept-clear point than the clearance
// (and nearer than they were), or that crossed one: its side of the face changed where it lies
// over the face before or after (a face that slid past it sideways within one step would not be
// caught; steps are a fraction of a pixel's parallax). `by_x`: the points sorted by x, so that a
// face looks only at those within its reach along x (thousands of cameras in a large scene).
void MarkFacesNearPoints(const Mesh& mesh, const std::vector<Eigen::Vector3d>& before,
                         const std::vector<uint8_t>& moving, const std::vector<uint8_t>& focus,
                         const std::vector<Eigen::Vector3d>& by_x, double clearance,
                         std::vector<uint8_t>* trouble) {
  if (by_x.empty()) return;
  const auto x_below = [](const Eigen::Vector3d& p, double x) { return p.x() < x; };
  for (size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    const auto& f = mesh.faces[fi];
    if (!focus[fi] || (!moving[f[0]] && !moving[f[1]] && !moving[f[2]])) continue;
    // A ball around the face before and after the move holds everything in between.
    Eigen::Vector3d middle = Eigen::Vector3d::Zero();
    for (int32_t v : f) middle += before[v] + mesh.vertices[v];
    middle /= 6;
    double radius = 0;
    for (int32_t v : f) {
      radius = std::max({radius, (before[v] - middle).norm(), (mesh.vertices[v] - middle).norm()});
    }
    const Eigen::Vector3d n0 = FaceCross(before, f), n1 = FaceCross(mesh.vertices, f);
    const auto& x = mesh.vertices;
    const std::array<Eigen::Vector3d, 3> then = {before[f[0]], before[f[1]], before[f[2]]};
    const std::array<Eigen::Vector3d, 3> now = {x[f[0]], x[f[1]], x[f[2]]};
    const double reach = radius + clearance;
    for (auto it = std::lower_bound(by_x.begin(), by_x.end(), middle.x() - reach, x_below);
         it != by_x.end() && it->x() <= middle.x() + reach; ++it) {
      const Eigen::Vector3d& p = *it;
      if ((p - middle).norm() > reach) continue;
      const double after = (p - ClosestPointOnTriangle(p, now)).norm();
      const bool near = after < clearance && after < (p - ClosestPointOnTriangle(p, then)).norm();
      const bool crossed = n0.dot(p - before[f[0]]) * n1.dot(p - x[f[0]]) < 0 &&
                           (PointOverTriangle(p, then) || PointOverTriangle(p, now));
      if (near || crossed) {
        for (int32_t v : f) (*trouble)[v] = 1;
      }
    }
  }
}

// One flag per face: set where a corner is flagged in `vertices`.
std::vector<uint8_t> FacesOf(const Mesh& mesh, const std::vector<uint8_t>& vertices) {
  std::vector<uint8_t> faces(mesh.faces.size(), 0);
  for (size_t f = 0; f < faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    faces[f] = vertices[t[0]] || vertices[t[1]] || vertices[t[2]];
  }
  return faces;
}

// Vertices of the checker's problems that involve a moving vertex.
void MarkCheckerProblems(const Mesh& mesh, const std::vector<uint8_t>& moving, double tolerance,
                         const std::vector<uint8_t>& focus, const PairCandidates* candidates,
                         std::vector<uint8_t>* trouble) {
  const CheckerProblems problems = FindCheckerProblems(mesh, tolerance, focus, candidates);
  const auto mark = [&](std::initializer_list<int32_t> vertices) {
    bool involved = false;
    for (int32_t v : vertices) involved = involved || moving[v];
    if (!involved) return;
    for (int32_t v : vertices) (*trouble)[v] = 1;
  };
  for (const auto& [f, g] : problems.face_pairs) {
    const auto &a = mesh.faces[f], &b = mesh.faces[g];
    mark({a[0], a[1], a[2], b[0], b[1], b[2]});
  }
  for (int64_t f : problems.degenerate_faces) {
    mark({mesh.faces[f][0], mesh.faces[f][1], mesh.faces[f][2]});
  }
  for (const auto& [u, v] : problems.vertex_pairs) mark({u, v});
}

}  // namespace

MoveStats MoveVerticesSafely(Mesh* mesh, const std::vector<Eigen::Vector3d>& displacement,
                             const MoveOptions& options, std::vector<uint8_t>* refused) {
  const size_t n = mesh->vertices.size();
  const std::vector<Eigen::Vector3d> before = mesh->vertices;
  std::vector<double> scale(n, 1.0);
  std::vector<int> halvings(n, 0);
  const double cos_limit = std::cos(options.max_face_turn_deg * M_PI / 180);
  MoveStats stats;
  // Only faces whose corners changed since the last check can have new problems: the first
  // check looks at the faces of moving vertices, each later one at those of vertices whose move
  // was just halved or dropped (against all faces).
  std::vector<uint8_t> changed(n, 0);
  for (size_t v = 0; v < n; ++v) changed[v] = displacement[v] != Eigen::Vector3d::Zero();
  // Every round's vertices lie between `before` and the full move (before + s x d, s in [0, 1],
  // is monotone in rounding too): one search over boxes that hold both gives every pair a
  // round's check can find, and each round tests those pairs instead of searching again.
  std::vector<Eigen::Vector3d> full_move(n);
  for (size_t v = 0; v < n; ++v) full_move[v] = before[v] + displacement[v];
  // (A tolerance of 0 leaves the checker its relative one, which the mesh's extent sets anew in
  // every round: no list then.)
  const bool listed = options.tolerance > 0;
  const PairCandidates candidates =
      listed ? FindPairCandidates(*mesh, full_move, options.tolerance, FacesOf(*mesh, changed))
             : PairCandidates();
  std::vector<Eigen::Vector3d> keep_clear_by_x = options.keep_clear;
  std::sort(keep_clear_by_x.begin(), keep_clear_by_x.end(),
            [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.x() < b.x(); });
  while (true) {
    std::vector<uint8_t> moving(n, 0);
    for (size_t v = 0; v < n; ++v) {
      moving[v] = scale[v] > 0 && displacement[v] != Eigen::Vector3d::Zero();
      mesh->vertices[v] = before[v] + scale[v] * displacement[v];
    }
    const std::vector<uint8_t> focus = FacesOf(*mesh, changed);
    std::vector<uint8_t> trouble(n, 0);
    MarkTurnedFaces(*mesh, before, moving, cos_limit, &trouble);
    MarkFacesNearPoints(*mesh, before, moving, focus, keep_clear_by_x, options.clearance, &trouble);
    MarkCheckerProblems(*mesh, moving, options.tolerance, focus, listed ? &candidates : nullptr,
                        &trouble);
    ++stats.rounds;
    bool any = false;
    std::fill(changed.begin(), changed.end(), 0);
    for (size_t v = 0; v < n; ++v) {
      if (!trouble[v] || !moving[v]) continue;
      any = true;
      changed[v] = 1;
      scale[v] = ++halvings[v] > options.max_halvings ? 0.0 : scale[v] / 2;
    }
    if (!any) break;
  }
  if (refused) refused->assign(n, 0);
  for (size_t v = 0; v < n; ++v) {
    if (displacement[v] == Eigen::Vector3d::Zero()) continue;
    if (scale[v] == 0) {
      if (refused) (*refused)[v] = 1;
      ++stats.refused;
      continue;
    }
    ++stats.moved;
    if (scale[v] < 1) ++stats.halved;
    stats.largest = std::max(stats.largest, scale[v] * displacement[v].norm());
  }
  return stats;
}

}  // namespace ms
