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

namespace {

// out's faces index `from`'s vertices: renumbers them in order of first use and gives out those
// vertices (and colours), each array allocated once at its size (at 10^6 vertices the output
// meshes are the coordinator's peak of memory).
void TakeReferencedVertices(const Mesh& from, Mesh* out) {
  std::vector<int32_t> remap(from.vertices.size(), -1);
  int32_t used = 0;
  for (auto& face : out->faces) {
    for (int32_t& v : face) {
      if (remap[v] < 0) remap[v] = used++;
      v = remap[v];
    }
  }
  std::vector<Eigen::Vector3d> kept(used);
  std::vector<std::array<uint8_t, 3>> kept_colors(from.HasColors() ? used : 0);
  for (size_t v = 0; v < remap.size(); ++v) {
    if (remap[v] < 0) continue;
    kept[remap[v]] = from.vertices[v];
    if (from.HasColors()) kept_colors[remap[v]] = from.vertex_colors[v];
  }
  out->vertices = std::move(kept);
  out->vertex_colors = std::move(kept_colors);
}

}  // namespace

void Mesh::RemoveUnreferencedVertices() { TakeReferencedVertices(*this, this); }

Mesh FacesWithoutFlaggedVertices(const Mesh& mesh, const std::vector<uint8_t>& flagged) {
  const auto kept = [&](const std::array<int32_t, 3>& f) {
    return !flagged[f[0]] && !flagged[f[1]] && !flagged[f[2]];
  };
  Mesh out;
  out.faces.reserve(std::count_if(mesh.faces.begin(), mesh.faces.end(), kept));
  for (const auto& f : mesh.faces) {
    if (kept(f)) out.faces.push_back(f);
  }
  TakeReferencedVertices(mesh, &out);
  return out;
}

namespace {

// Faces around each vertex, compressed: the faces of v are incident[offsets[v]..offsets[v+1]),
// in face order. Rebuilt per pass, without an allocation per vertex.
struct VertexFaces {
  std::vector<int64_t> offsets;
  std::vector<int32_t> incident;

  void Build(const Mesh& mesh) {
    const size_t nv = mesh.vertices.size();
    offsets.assign(nv + 1, 0);
    for (const auto& f : mesh.faces) {
      for (int32_t v : f) ++offsets[v + 1];
    }
    for (size_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
    incident.resize(offsets[nv]);
    std::vector<int64_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      for (int32_t v : mesh.faces[f]) incident[fill[v]++] = static_cast<int32_t>(f);
    }
  }
};

// Appends to `drop` the faces around v (`around`, `count` of them, in face order) outside its
// largest fan: faces are one fan when joined through edges at v (union-find over the faces,
// joined when they share the edge's other vertex). Ties go to the fan of the first face.
class FanSplitter {
 public:
  void SmallerFans(int32_t v, const int32_t* around, size_t count,
                   const std::vector<std::array<int32_t, 3>>& faces, std::vector<int32_t>* drop) {
    parent_.resize(count);
    for (size_t i = 0; i < count; ++i) parent_[i] = static_cast<int>(i);
    by_other_.clear();
    for (size_t i = 0; i < count; ++i) {
      for (int32_t w : faces[around[i]]) {
        if (w != v) by_other_.emplace_back(w, static_cast<int>(i));
      }
    }
    std::sort(by_other_.begin(), by_other_.end());
    size_t fans = count;
    for (size_t k = 1; k < by_other_.size(); ++k) {
      if (by_other_[k].first != by_other_[k - 1].first) continue;
      const int a = Find(by_other_[k].second), b = Find(by_other_[k - 1].second);
      if (a != b) {
        parent_[a] = b;
        --fans;
      }
    }
    if (fans == 1) return;
    size_.assign(count, 0);
    for (size_t i = 0; i < count; ++i) ++size_[Find(static_cast<int>(i))];
    int keep = -1;
    for (size_t i = 0; i < count; ++i) {
      const int root = Find(static_cast<int>(i));
      if (keep < 0 || size_[root] > size_[keep]) keep = root;
    }
    for (size_t i = 0; i < count; ++i) {
      if (Find(static_cast<int>(i)) != keep) drop->push_back(around[i]);
    }
  }

 private:
  int Find(int i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  std::vector<int> parent_, size_;
  std::vector<std::pair<int32_t, int>> by_other_;  // (other vertex of an edge at v, face)
};

}  // namespace

int64_t KeepOneFanPerVertex(Mesh* mesh) {
  int64_t removed = 0;
  VertexFaces adjacency;
  FanSplitter splitter;
  // Every vertex on the first pass; afterwards only those of removed faces can have split.
  std::vector<uint8_t> look(mesh->vertices.size(), 1);
  for (;;) {
    adjacency.Build(*mesh);
    std::vector<int32_t> drop;
    for (size_t v = 0; v < look.size(); ++v) {
      const int64_t begin = adjacency.offsets[v], end = adjacency.offsets[v + 1];
      if (!look[v] || end - begin < 2) continue;
      splitter.SmallerFans(static_cast<int32_t>(v), &adjacency.incident[begin],
                           static_cast<size_t>(end - begin), mesh->faces, &drop);
    }
    if (drop.empty()) break;
    std::sort(drop.begin(), drop.end());
    drop.erase(std::unique(drop.begin(), drop.end()), drop.end());
    adjacency = VertexFaces();  // made again on the next pass; less held meanwhile
    std::fill(look.begin(), look.end(), 0);
    // The kept faces moved down in place, in their order.
    size_t kept = 0;
    for (size_t f = 0, d = 0; f < mesh->faces.size(); ++f) {
      if (d < drop.size() && drop[d] == static_cast<int32_t>(f)) {
        ++d;
        for (int32_t v : mesh->faces[f]) look[v] = 1;
      } else {
        mesh->faces[kept++] = mesh->faces[f];
      }
    }
    removed += static_cast<int64_t>(drop.size());
    mesh->faces.resize(kept);
  }
  mesh->RemoveUnreferencedVertices();
  return removed;
}

}  // namespace ms
