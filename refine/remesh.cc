#include "refine/remesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <iterator>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "base/check.h"
#include "base/error.h"
#include "mesh/face_grid.h"
#include "refine/mesh_moves.h"

namespace ms {
namespace {

using Edge = std::pair<int32_t, int32_t>;  // (smaller, larger) vertex index

Edge Key(int32_t a, int32_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

// Whether an edge has a frozen end (flags for the vertices the step was given; later ones are
// free).
bool HasFrozenEnd(const std::vector<uint8_t>& frozen, const Edge& edge) {
  const auto is_frozen = [&](int32_t v) {
    return static_cast<size_t>(v) < frozen.size() && frozen[static_cast<size_t>(v)];
  };
  return is_frozen(edge.first) || is_frozen(edge.second);
}

// Every edge with the faces that have it (one on a boundary, two inside, in face order), sorted
// by edge: a flat table built by one sort (a map of vectors cost two allocations an edge). An
// edge in more than two faces is an InternalError naming `who`.
class EdgeFaceTable {
 public:
  struct Faces {
    int32_t face[2] = {-1, -1};
    int32_t count = 0;
    size_t size() const { return static_cast<size_t>(count); }
    int32_t operator[](size_t i) const { return face[i]; }
    const int32_t* begin() const { return face; }
    const int32_t* end() const { return face + count; }
  };
  struct Entry {
    Edge edge;
    Faces faces;
  };

  EdgeFaceTable(const Mesh& mesh, const char* who) {
    std::vector<std::pair<Edge, int32_t>> sides;
    sides.reserve(3 * mesh.faces.size());
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const auto& t = mesh.faces[f];
      for (int k = 0; k < 3; ++k) {
        sides.push_back({Key(t[k], t[(k + 1) % 3]), static_cast<int32_t>(f)});
      }
    }
    std::sort(sides.begin(), sides.end());
    for (const auto& [edge, f] : sides) {
      if (entries_.empty() || entries_.back().edge != edge) entries_.push_back({edge, {}});
      Faces& faces = entries_.back().faces;
      if (faces.count == 2) {
        throw InternalError(std::string(who) + ": an edge is in more than two faces");
      }
      faces.face[faces.count++] = f;
    }
  }

  std::vector<Entry>::const_iterator begin() const { return entries_.begin(); }
  std::vector<Entry>::const_iterator end() const { return entries_.end(); }
  bool Has(const Edge& edge) const { return Find(edge) != entries_.end(); }
  // The faces of an edge of the mesh.
  const Faces& At(const Edge& edge) const {
    const auto it = Find(edge);
    MS_CHECK(it != entries_.end()) << "edge " << edge.first << "-" << edge.second;
    return it->faces;
  }

 private:
  std::vector<Entry>::const_iterator Find(const Edge& edge) const {
    const auto it = std::lower_bound(entries_.begin(), entries_.end(), edge,
                                     [](const Entry& e, const Edge& x) { return e.edge < x; });
    return it != entries_.end() && it->edge == edge ? it : entries_.end();
  }

  std::vector<Entry> entries_;
};

// The faces the checker objects to: both faces of each pair, and the degenerate ones.
std::vector<int64_t> TroubledFaces(const CheckerProblems& problems) {
  std::vector<int64_t> faces = problems.degenerate_faces;
  for (const auto& [f, g] : problems.face_pairs) {
    faces.push_back(f);
    faces.push_back(g);
  }
  return faces;
}

// The checker's problems among the faces flagged in `focus`: looked for among the grid's
// candidates where few faces are flagged, by a box search where many are (it sorts every face's
// box once, where the grid looks around each flagged face).
CheckerProblems FindProblemsNear(const Mesh& mesh, double tolerance,
                                 const std::vector<uint8_t>& focus, const FaceGrid& grid) {
  const auto flagged = std::count(focus.begin(), focus.end(), 1);
  if (8 * static_cast<size_t>(flagged) > focus.size()) {
    return FindCheckerProblems(mesh, tolerance, focus);
  }
  const PairCandidates candidates = grid.Candidates(mesh, focus);
  return FindCheckerProblems(mesh, tolerance, focus, &candidates);
}

// One split: edge (u, v) of faces f0 and f1 at the new vertex m; faces f0 and f1 were changed
// and faces added0 and added1 appended.
struct Split {
  Edge edge;
  int32_t m;
  int num_faces;  // 2, or 1 on a boundary
  int32_t faces[2], added[2];
  std::array<int32_t, 3> old_faces[2];
};

// The split point: the edge's midpoint, moved off the edge along the mean of its faces'
// normals by `offset`. Exactly on the edge, a chain of splits along a crease leaves collinear
// vertices whose faces double-precision tests (Open3D's among them) find touching.
Eigen::Vector3d SplitPoint(const Mesh& mesh, const Edge& edge, const EdgeFaceTable::Faces& faces,
                           double offset) {
  const Eigen::Vector3d mid = 0.5 * (mesh.vertices[edge.first] + mesh.vertices[edge.second]);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int32_t f : faces) n += FaceCross(mesh.vertices, mesh.faces[f]).normalized();
  return n.norm() > 1e-6 ? Eigen::Vector3d(mid + offset * n.normalized()) : mid;
}

// One pass: the edges longer than their limit (and not refused before), longest first, each
// split unless one of its two faces was already split in this pass.
std::vector<Split> SplitPass(Mesh* mesh,
                             const std::function<double(const Eigen::Vector3d&)>& max_length,
                             int64_t max_vertices, const std::set<Edge>& refused, double offset,
                             const std::vector<uint8_t>& frozen) {
  const EdgeFaceTable faces_of(*mesh, "SplitLongEdges");
  std::vector<std::pair<double, Edge>> long_edges;
  for (const auto& [edge, faces] : faces_of) {
    if (refused.count(edge) || HasFrozenEnd(frozen, edge)) continue;
    const Eigen::Vector3d& a = mesh->vertices[edge.first];
    const Eigen::Vector3d& b = mesh->vertices[edge.second];
    const double length = (a - b).norm();
    if (length > max_length(0.5 * (a + b))) long_edges.emplace_back(length, edge);
  }
  std::sort(long_edges.begin(), long_edges.end(), [](const auto& x, const auto& y) {
    return x.first > y.first || (x.first == y.first && x.second < y.second);
  });
  std::vector<uint8_t> touched(mesh->faces.size(), 0);
  std::vector<Split> splits;
  for (const auto& [length, edge] : long_edges) {
    if (static_cast<int64_t>(mesh->vertices.size()) >= max_vertices) break;
    const EdgeFaceTable::Faces& faces = faces_of.At(edge);
    if (touched[faces[0]] || (faces.size() == 2 && touched[faces[1]])) continue;
    Split s;
    s.edge = edge;
    s.m = static_cast<int32_t>(mesh->vertices.size());
    s.num_faces = static_cast<int>(faces.size());
    mesh->vertices.push_back(SplitPoint(*mesh, edge, faces, offset));
    for (int i = 0; i < s.num_faces; ++i) {
      // Rotate the face so that the split edge comes first: (u, v, w) with {u, v} = edge
      // becomes (u, m, w) and (m, v, w), keeping its orientation.
      const int32_t f = faces[i];
      s.faces[i] = f;
      s.old_faces[i] = mesh->faces[f];
      std::array<int32_t, 3> t = mesh->faces[f];
      while (Key(t[0], t[1]) != edge) std::rotate(t.begin(), t.begin() + 1, t.end());
      mesh->faces[f] = {t[0], s.m, t[2]};
      s.added[i] = static_cast<int32_t>(mesh->faces.size());
      mesh->faces.push_back({s.m, t[1], t[2]});
      touched[f] = 1;
      touched.push_back(1);
    }
    splits.push_back(s);
  }
  return splits;
}

// Undoes the splits of this pass whose faces or new vertex the checker objects to, until it
// objects to none of them (what is left was there before the pass); the remaining splits' face
// indices follow the removal of the undone ones' faces. Returns how many were undone.
int64_t UndoTroubledSplits(Mesh* mesh, std::vector<Split>* splits_ptr, double tolerance,
                           std::set<Edge>* refused, FaceGrid* grid) {
  std::vector<Split>& splits = *splits_ptr;  // face indices are renumbered as faces go
  int64_t undone = 0;
  std::vector<uint8_t> alive(splits.size(), 1);
  // The faces the pass changed; later, those of undone splits (their old faces are back).
  std::vector<uint8_t> focus(mesh->faces.size(), 0);
  for (const Split& s : splits) {
    for (int k = 0; k < s.num_faces; ++k) focus[s.faces[k]] = focus[s.added[k]] = 1;
  }
  while (true) {
    const CheckerProblems problems = FindProblemsNear(*mesh, tolerance, focus, *grid);
    if (problems.Empty()) break;
    // The split that made each face or vertex.
    std::map<int64_t, size_t> by_face;
    std::map<int32_t, size_t> by_vertex;
    for (size_t i = 0; i < splits.size(); ++i) {
      if (!alive[i]) continue;
      for (int k = 0; k < splits[i].num_faces; ++k) {
        by_face[splits[i].faces[k]] = i;
        by_face[splits[i].added[k]] = i;
      }
      by_vertex[splits[i].m] = i;
    }
    std::set<size_t> bad;
    for (int64_t f : TroubledFaces(problems)) {
      if (auto it = by_face.find(f); it != by_face.end()) bad.insert(it->second);
    }
    for (const auto& pair : problems.vertex_pairs) {
      for (int32_t v : pair) {
        if (auto it = by_vertex.find(v); it != by_vertex.end()) bad.insert(it->second);
      }
    }
    if (bad.empty()) break;  // what is left was there before the pass
    std::vector<uint8_t> restored(mesh->faces.size(), 0);
    for (size_t i : bad) {
      const Split& s = splits[i];
      for (int k = 0; k < s.num_faces; ++k) {
        restored[s.faces[k]] = 1;
        mesh->faces[s.faces[k]] = s.old_faces[k];
        mesh->faces[s.added[k]] = {s.m, s.m, s.m};  // dead: removed below
      }
      alive[i] = 0;
      refused->insert(s.edge);
      ++undone;
    }
    // Dead faces are degenerate and would be reported: drop them now (indices of the
    // remaining splits' faces shift, so renumber them).
    std::vector<int64_t> new_index(mesh->faces.size(), -1);
    std::vector<std::array<int32_t, 3>> kept;
    focus.clear();
    for (size_t f = 0; f < mesh->faces.size(); ++f) {
      const auto& t = mesh->faces[f];
      if (t[0] == t[1] && t[1] == t[2]) continue;
      new_index[f] = static_cast<int64_t>(kept.size());
      kept.push_back(t);
      focus.push_back(restored[f]);
    }
    mesh->faces = std::move(kept);
    grid->Renumber(new_index);
    for (size_t f = 0; f < focus.size(); ++f) {
      if (focus[f]) grid->Update(*mesh, static_cast<int32_t>(f));  // restored
    }
    for (size_t i = 0; i < splits.size(); ++i) {
      if (!alive[i]) continue;
      Split& s = splits[i];
      for (int k = 0; k < s.num_faces; ++k) {
        s.faces[k] = static_cast<int32_t>(new_index[s.faces[k]]);
        s.added[k] = static_cast<int32_t>(new_index[s.added[k]]);
      }
    }
  }
  return undone;
}

}  // namespace

SplitStats SplitLongEdges(Mesh* mesh,
                          const std::function<double(const Eigen::Vector3d&)>& max_length,
                          int64_t max_vertices, double tolerance,
                          const std::vector<uint8_t>& frozen) {
  SplitStats stats;
  std::set<Edge> refused;
  FaceGrid grid(*mesh, tolerance);
  while (static_cast<int64_t>(mesh->vertices.size()) < max_vertices) {
    const size_t faces_before = mesh->faces.size();
    std::vector<Split> splits =
        SplitPass(mesh, max_length, max_vertices, refused, 8 * tolerance, frozen);
    ++stats.rounds;
    if (splits.empty()) break;
    for (const Split& s : splits) {
      for (int k = 0; k < s.num_faces; ++k) grid.Update(*mesh, s.faces[k]);
    }
    for (size_t f = faces_before; f < mesh->faces.size(); ++f) {
      grid.Update(*mesh, static_cast<int32_t>(f));
    }
    const int64_t undone = UndoTroubledSplits(mesh, &splits, tolerance, &refused, &grid);
    stats.splits += static_cast<int64_t>(splits.size()) - undone;
    stats.refused += undone;
  }
  mesh->RemoveUnreferencedVertices();
  return stats;
}

namespace {

// One flip: faces f0 = (a, b, c) and f1 = (b, a, d) of edge (a, b) became (c, a, d) and
// (d, b, c).
struct Flip {
  Edge edge;  // (a, b)
  int32_t faces[2];
  std::array<int32_t, 3> old_faces[2];
};

double Angle(const Eigen::Vector3d& at, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d u = p - at, v = q - at;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

// One pass over the edges in index order; a face flips at most once per pass.
std::vector<Flip> FlipPass(Mesh* mesh, double min_cos_dihedral, const std::set<Edge>& refused,
                           const std::vector<uint8_t>& frozen) {
  const EdgeFaceTable faces_of(*mesh, "FlipEdges");
  std::vector<int32_t> degree(mesh->vertices.size(), 0);
  for (const auto& entry : faces_of) {
    ++degree[entry.edge.first];
    ++degree[entry.edge.second];
  }
  std::vector<uint8_t> touched(mesh->faces.size(), 0);
  std::set<Edge> created;  // by this pass's flips
  std::vector<Flip> flips;
  for (const auto& [edge, faces] : faces_of) {
    if (faces.size() != 2 || touched[faces[0]] || touched[faces[1]] || refused.count(edge) ||
        HasFrozenEnd(frozen, edge)) {
      continue;
    }
    // f0 has the edge as a -> b, f1 as b -> a (consistent orientation).
    std::array<int32_t, 3> t0 = mesh->faces[faces[0]], t1 = mesh->faces[faces[1]];
    while (Key(t0[0], t0[1]) != edge) std::rotate(t0.begin(), t0.begin() + 1, t0.end());
    while (Key(t1[0], t1[1]) != edge) std::rotate(t1.begin(), t1.begin() + 1, t1.end());
    const int32_t a = t0[0], b = t0[1], c = t0[2], d = t1[2];
    if (t1[0] != b || t1[1] != a || c == d) continue;  // not consistently oriented: leave it
    if (degree[a] <= 3 || degree[b] <= 3 || faces_of.Has(Key(c, d)) || created.count(Key(c, d))) {
      continue;
    }
    const Eigen::Vector3d &pa = mesh->vertices[a], &pb = mesh->vertices[b];
    const Eigen::Vector3d &pc = mesh->vertices[c], &pd = mesh->vertices[d];
    if (Angle(pc, pa, pb) + Angle(pd, pa, pb) <= M_PI + 1e-9) continue;  // Delaunay already
    const Eigen::Vector3d n0 = FaceCross(mesh->vertices, t0).normalized();
    const Eigen::Vector3d n1 = FaceCross(mesh->vertices, t1).normalized();
    if (!(n0.dot(n1) >= min_cos_dihedral)) continue;
    const std::array<int32_t, 3> new0 = {c, a, d}, new1 = {d, b, c};
    const Eigen::Vector3d m0 = FaceCross(mesh->vertices, new0),
                          m1 = FaceCross(mesh->vertices, new1);
    const Eigen::Vector3d mean = n0 + n1;
    if (!(m0.dot(mean) > 0 && m1.dot(mean) > 0 &&
          m0.normalized().dot(m1.normalized()) >= min_cos_dihedral)) {
      continue;
    }
    Flip flip;
    flip.edge = edge;
    for (int i = 0; i < 2; ++i) {
      flip.faces[i] = faces[i];
      flip.old_faces[i] = mesh->faces[faces[i]];
      touched[faces[i]] = 1;
    }
    mesh->faces[faces[0]] = new0;
    mesh->faces[faces[1]] = new1;
    --degree[a];
    --degree[b];
    ++degree[c];
    ++degree[d];
    created.insert(Key(c, d));
    flips.push_back(flip);
  }
  return flips;
}

}  // namespace

FlipStats FlipEdges(Mesh* mesh, double max_dihedral_deg, double tolerance,
                    const std::vector<uint8_t>& frozen, int max_rounds) {
  FlipStats stats;
  const double min_cos = std::cos(max_dihedral_deg * M_PI / 180);
  std::set<Edge> refused;
  FaceGrid grid(*mesh, tolerance);
  for (int round = 0; round < max_rounds; ++round) {
    std::vector<Flip> flips = FlipPass(mesh, min_cos, refused, frozen);
    ++stats.rounds;
    if (flips.empty()) break;
    for (const Flip& flip : flips) {
      for (int32_t f : flip.faces) grid.Update(*mesh, f);
    }
    std::vector<uint8_t> alive(flips.size(), 1), focus(mesh->faces.size(), 0);
    std::map<int64_t, size_t> by_face;
    for (size_t i = 0; i < flips.size(); ++i) {
      for (int32_t f : flips[i].faces) {
        focus[f] = 1;
        by_face[f] = i;
      }
    }
    int64_t undone = 0;
    while (true) {
      const CheckerProblems problems = FindProblemsNear(*mesh, tolerance, focus, grid);
      std::set<size_t> bad;
      for (int64_t f : TroubledFaces(problems)) {
        if (auto it = by_face.find(f); it != by_face.end() && alive[it->second]) {
          bad.insert(it->second);
        }
      }
      if (bad.empty()) break;  // what is left was there before the pass
      std::fill(focus.begin(), focus.end(), 0);
      for (size_t i : bad) {
        const Flip& flip = flips[i];
        for (int k = 0; k < 2; ++k) {
          mesh->faces[flip.faces[k]] = flip.old_faces[k];
          grid.Update(*mesh, flip.faces[k]);
          focus[flip.faces[k]] = 1;
        }
        refused.insert(flip.edge);  // not tried again
        alive[i] = 0;
        ++undone;
      }
    }
    stats.flips += static_cast<int64_t>(flips.size()) - undone;
    stats.refused += undone;
  }
  return stats;
}

namespace {

// A planned collapse: vertex `gone` merges into `kept`, both at the edge's midpoint.
struct Collapse {
  Edge edge;
  int32_t kept, gone;
  Eigen::Vector3d position;
};

// The collapses of one pass: short edges, shortest first, each allowed by the link condition
// and the face-turn limit, none touching another's star.
std::vector<Collapse> PlanCollapses(const Mesh& mesh,
                                    const std::function<double(const Eigen::Vector3d&)>& min_length,
                                    double cos_turn, const std::set<Edge>& refused,
                                    const std::vector<uint8_t>& frozen) {
  const EdgeFaceTable faces_of(mesh, "CollapseShortEdges");
  std::vector<std::vector<int32_t>> faces_at(mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int32_t v : mesh.faces[f]) faces_at[v].push_back(static_cast<int32_t>(f));
  }
  const std::vector<std::vector<int32_t>> neighbours = VertexNeighbours(mesh);
  std::vector<std::pair<double, Edge>> short_edges;
  std::vector<uint8_t> on_boundary(mesh.vertices.size(), 0);
  for (const auto& [edge, faces] : faces_of) {
    if (faces.size() == 1) on_boundary[edge.first] = on_boundary[edge.second] = 1;
  }
  for (const auto& [edge, faces] : faces_of) {
    if (refused.count(edge) || on_boundary[edge.first] || on_boundary[edge.second] ||
        HasFrozenEnd(frozen, edge)) {
      continue;
    }
    const Eigen::Vector3d& a = mesh.vertices[edge.first];
    const Eigen::Vector3d& b = mesh.vertices[edge.second];
    const double length = (a - b).norm();
    if (length < min_length(0.5 * (a + b))) short_edges.emplace_back(length, edge);
  }
  std::sort(short_edges.begin(), short_edges.end());
  std::vector<uint8_t> locked(mesh.vertices.size(), 0);
  int64_t vertices_left = static_cast<int64_t>(mesh.vertices.size());
  std::vector<Collapse> plan;
  for (const auto& [length, edge] : short_edges) {
    const int32_t a = edge.first, b = edge.second;
    if (vertices_left <= 4 || locked[a] || locked[b]) continue;
    // The link condition: the common neighbours are exactly the two opposite vertices.
    std::vector<int32_t> common;
    std::set_intersection(neighbours[a].begin(), neighbours[a].end(), neighbours[b].begin(),
                          neighbours[b].end(), std::back_inserter(common));
    if (common.size() != 2) continue;
    if (neighbours[common[0]].size() <= 3 || neighbours[common[1]].size() <= 3) continue;
    bool free = true;
    for (int32_t v : {a, b}) {
      for (int32_t u : neighbours[v]) free = free && !locked[u];
    }
    if (!free) continue;
    const Eigen::Vector3d mid = 0.5 * (mesh.vertices[a] + mesh.vertices[b]);
    // Every face that stays turns by at most the limit (and so does not flip).
    bool turns_ok = true;
    for (int32_t v : {a, b}) {
      for (int32_t f : faces_at[v]) {
        std::array<int32_t, 3> t = mesh.faces[f];
        if (std::count(t.begin(), t.end(), a) && std::count(t.begin(), t.end(), b)) continue;
        const Eigen::Vector3d before = FaceCross(mesh.vertices, t);
        Eigen::Vector3d p[3];
        for (int k = 0; k < 3; ++k) p[k] = (t[k] == a || t[k] == b) ? mid : mesh.vertices[t[k]];
        const Eigen::Vector3d after = (p[1] - p[0]).cross(p[2] - p[0]);
        const double n = before.norm() * after.norm();
        if (!(n > 0 && before.dot(after) >= cos_turn * n)) turns_ok = false;
      }
    }
    if (!turns_ok) continue;
    for (int32_t v : {a, b}) {
      locked[v] = 1;
      for (int32_t u : neighbours[v]) locked[u] = 1;
    }
    plan.push_back({edge, a, b, mid});
    --vertices_left;
  }
  return plan;
}

// `mesh` with the planned collapses made: the collapsed edges' faces gone, `gone` vertices
// unreferenced (still in place), `kept` ones at the midpoints. owner[f] is the collapse whose
// star face f is in (-1: none).
Mesh ApplyCollapses(const Mesh& mesh, const std::vector<Collapse>& plan,
                    std::vector<int32_t>* owner) {
  Mesh out;
  out.vertices = mesh.vertices;
  std::vector<int32_t> merged(mesh.vertices.size(), -1);  // gone -> kept
  std::vector<int32_t> collapse_of(mesh.vertices.size(), -1);
  for (size_t i = 0; i < plan.size(); ++i) {
    merged[plan[i].gone] = plan[i].kept;
    out.vertices[plan[i].kept] = plan[i].position;
    collapse_of[plan[i].kept] = collapse_of[plan[i].gone] = static_cast<int32_t>(i);
  }
  owner->clear();
  for (auto t : mesh.faces) {
    int32_t by = -1;
    for (int32_t& v : t) {
      if (collapse_of[v] >= 0) by = collapse_of[v];
      if (merged[v] >= 0) v = merged[v];
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;  // a collapsed edge's face
    out.faces.push_back(t);
    owner->push_back(by);
  }
  return out;
}

}  // namespace

CollapseStats CollapseShortEdges(Mesh* mesh,
                                 const std::function<double(const Eigen::Vector3d&)>& min_length,
                                 double max_face_turn_deg, double tolerance,
                                 const std::vector<uint8_t>& frozen, int max_rounds) {
  CollapseStats stats;
  const double cos_turn = std::cos(max_face_turn_deg * M_PI / 180);
  std::set<Edge> refused;
  for (int round = 0; round < max_rounds; ++round) {
    std::vector<Collapse> plan = PlanCollapses(*mesh, min_length, cos_turn, refused, frozen);
    ++stats.rounds;
    if (plan.empty()) break;
    while (!plan.empty()) {
      std::vector<int32_t> owner;
      Mesh trial = ApplyCollapses(*mesh, plan, &owner);
      std::vector<uint8_t> focus(owner.size());
      for (size_t f = 0; f < owner.size(); ++f) focus[f] = owner[f] >= 0;
      const CheckerProblems problems = FindCheckerProblems(trial, tolerance, focus);
      std::set<int32_t> bad;
      for (int64_t f : TroubledFaces(problems)) {
        if (owner[f] >= 0) bad.insert(owner[f]);
      }
      for (const auto& [u, v] : problems.vertex_pairs) {
        for (size_t i = 0; i < plan.size(); ++i) {
          if (plan[i].kept == u || plan[i].kept == v) bad.insert(static_cast<int32_t>(i));
        }
      }
      if (bad.empty()) {
        stats.collapses += static_cast<int64_t>(plan.size());
        *mesh = std::move(trial);
        break;
      }
      std::vector<Collapse> kept;
      for (size_t i = 0; i < plan.size(); ++i) {
        if (bad.count(static_cast<int32_t>(i))) {
          refused.insert(plan[i].edge);
          ++stats.refused;
        } else {
          kept.push_back(plan[i]);
        }
      }
      plan = std::move(kept);
    }
  }
  mesh->RemoveUnreferencedVertices();
  return stats;
}

}  // namespace ms
