#include "mesh/mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <utility>

namespace ms {

Eigen::Vector3d Mesh::FaceNormal(size_t f) const {
  const auto& t = faces[f];
  const Eigen::Vector3d n =
      (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

double Mesh::FaceArea(size_t f) const {
  const auto& t = faces[f];
  return 0.5 * (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
}

double Mesh::SurfaceArea() const {
  double area = 0;
  for (size_t f = 0; f < faces.size(); ++f) area += FaceArea(f);
  return area;
}

void Mesh::RemoveUnreferencedVertices() {
  std::vector<int32_t> remap(vertices.size(), -1);
  std::vector<Eigen::Vector3d> kept;
  std::vector<std::array<uint8_t, 3>> kept_colors;
  for (auto& face : faces) {
    for (int32_t& v : face) {
      if (remap[v] < 0) {
        remap[v] = static_cast<int32_t>(kept.size());
        kept.push_back(vertices[v]);
        if (HasColors()) kept_colors.push_back(vertex_colors[v]);
      }
      v = remap[v];
    }
  }
  vertices = std::move(kept);
  vertex_colors = std::move(kept_colors);
}

Mesh FacesWithoutFlaggedVertices(const Mesh& mesh, const std::vector<uint8_t>& flagged) {
  Mesh out;
  out.vertices = mesh.vertices;
  out.vertex_colors = mesh.vertex_colors;
  for (const auto& f : mesh.faces) {
    if (!flagged[f[0]] && !flagged[f[1]] && !flagged[f[2]]) out.faces.push_back(f);
  }
  out.RemoveUnreferencedVertices();
  return out;
}

namespace {

// Faces (indices into `faces`) of the fans around one vertex other than its largest.
void SmallerFans(int32_t v, const std::vector<int32_t>& around,
                 const std::vector<std::array<int32_t, 3>>& faces, std::vector<int32_t>* drop) {
  // Union-find over the faces around v: two are one fan when they share an edge at v.
  std::vector<int> parent(around.size());
  for (size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  const auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<std::pair<int32_t, int>> by_other;  // (other vertex of an edge at v, face)
  for (size_t i = 0; i < around.size(); ++i) {
    for (int32_t w : faces[around[i]]) {
      if (w != v) by_other.emplace_back(w, static_cast<int>(i));
    }
  }
  std::sort(by_other.begin(), by_other.end());
  for (size_t k = 1; k < by_other.size(); ++k) {
    if (by_other[k].first == by_other[k - 1].first) {
      parent[find(by_other[k].second)] = find(by_other[k - 1].second);
    }
  }
  std::vector<int> size(around.size(), 0);
  for (size_t i = 0; i < around.size(); ++i) ++size[find(static_cast<int>(i))];
  int keep = -1;
  for (size_t i = 0; i < around.size(); ++i) {  // around is in face order: ties to the first
    const int root = find(static_cast<int>(i));
    if (keep < 0 || size[root] > size[keep]) keep = root;
  }
  for (size_t i = 0; i < around.size(); ++i) {
    if (find(static_cast<int>(i)) != keep) drop->push_back(around[i]);
  }
}

}  // namespace

int64_t KeepOneFanPerVertex(Mesh* mesh) {
  int64_t removed = 0;
  for (;;) {
    std::vector<std::vector<int32_t>> around(mesh->vertices.size());
    for (size_t f = 0; f < mesh->faces.size(); ++f) {
      for (int32_t v : mesh->faces[f]) around[v].push_back(static_cast<int32_t>(f));
    }
    std::vector<int32_t> drop;
    for (size_t v = 0; v < around.size(); ++v) {
      if (around[v].size() > 1) SmallerFans(static_cast<int32_t>(v), around[v], mesh->faces, &drop);
    }
    if (drop.empty()) break;
    std::sort(drop.begin(), drop.end());
    drop.erase(std::unique(drop.begin(), drop.end()), drop.end());
    std::vector<std::array<int32_t, 3>> kept;
    kept.reserve(mesh->faces.size() - drop.size());
    for (size_t f = 0, d = 0; f < mesh->faces.size(); ++f) {
      if (d < drop.size() && drop[d] == static_cast<int32_t>(f)) {
        ++d;
      } else {
        kept.push_back(mesh->faces[f]);
      }
    }
    removed += static_cast<int64_t>(drop.size());
    mesh->faces = std::move(kept);
  }
  mesh->RemoveUnreferencedVertices();
  return removed;
}

}  // namespace ms
