#include "refine/remesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <climits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "base/error.h"
#include "refine/mesh_moves.h"

namespace ms {
namespace {

using Edge = std::pair<int32_t, int32_t>;  // (smaller, larger) vertex index

Edge Key(int32_t a, int32_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

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
Eigen::Vector3d SplitPoint(const Mesh& mesh, const Edge& edge, const std::vector<int32_t>& faces,
                           double offset) {
  const Eigen::Vector3d mid = 0.5 * (mesh.vertices[edge.first] + mesh.vertices[edge.second]);
  const auto normal = [&](const std::array<int32_t, 3>& f) {
    return (mesh.vertices[f[1]] - mesh.vertices[f[0]])
        .cross(mesh.vertices[f[2]] - mesh.vertices[f[0]])
        .normalized();
  };
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int32_t f : faces) n += normal(mesh.faces[f]);
  return n.norm() > 1e-6 ? Eigen::Vector3d(mid + offset * n.normalized()) : mid;
}

// One pass: the edges longer than their limit (and not refused before), longest first, each
// split unless one of its two faces was already split in this pass.
std::vector<Split> SplitPass(Mesh* mesh,
                             const std::function<double(const Eigen::Vector3d&)>& max_length,
                             int64_t max_vertices, const std::set<Edge>& refused, double offset) {
  std::map<Edge, std::vector<int32_t>> faces_of;  // edge -> the faces that have it
  for (size_t f = 0; f < mesh->faces.size(); ++f) {
    const auto& t = mesh->faces[f];
    for (int k = 0; k < 3; ++k) {
      faces_of[Key(t[k], t[(k + 1) % 3])].push_back(static_cast<int32_t>(f));
    }
  }
  std::vector<std::pair<double, Edge>> long_edges;
  for (const auto& [edge, faces] : faces_of) {
    if (faces.size() > 2) throw InternalError("SplitLongEdges: an edge is in more than two faces");
    if (refused.count(edge)) continue;
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
    const std::vector<int32_t>& faces = faces_of[edge];
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
                           std::set<Edge>* refused) {
  std::vector<Split>& splits = *splits_ptr;  // face indices are renumbered as faces go
  int64_t undone = 0;
  std::vector<uint8_t> alive(splits.size(), 1);
  // The faces the pass changed; later, those of undone splits (their old faces are back).
  std::vector<uint8_t> focus(mesh->faces.size(), 0);
  for (const Split& s : splits) {
    for (int k = 0; k < s.num_faces; ++k) focus[s.faces[k]] = focus[s.added[k]] = 1;
  }
  while (true) {
    const CheckerProblems problems = FindCheckerProblems(*mesh, tolerance, focus);
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
    const auto bad_face = [&](int64_t f) {
      if (auto it = by_face.find(f); it != by_face.end()) bad.insert(it->second);
    };
    const auto bad_vertex = [&](int32_t v) {
      if (auto it = by_vertex.find(v); it != by_vertex.end()) bad.insert(it->second);
    };
    for (const auto& [f, g] : problems.face_pairs) {
      bad_face(f);
      bad_face(g);
    }
    for (int64_t f : problems.degenerate_faces) bad_face(f);
    for (const auto& [u, v] : problems.vertex_pairs) {
      bad_vertex(u);
      bad_vertex(v);
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
                          int64_t max_vertices, double tolerance) {
  SplitStats stats;
  std::set<Edge> refused;
  while (static_cast<int64_t>(mesh->vertices.size()) < max_vertices) {
    std::vector<Split> splits = SplitPass(mesh, max_length, max_vertices, refused, 8 * tolerance);
    ++stats.rounds;
    if (splits.empty()) break;
    const int64_t undone = UndoTroubledSplits(mesh, &splits, tolerance, &refused);
    stats.splits += static_cast<int64_t>(splits.size()) - undone;
    stats.refused += undone;
  }
  mesh->RemoveUnreferencedVertices();
  return stats;
}

}  // namespace ms
