#include "testing/test_meshes.h"

#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace ms::test_meshes {

void OrientOutward(Mesh* m) {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  for (const auto& v : m->vertices) center += v;
  center /= static_cast<double>(m->vertices.size());
  for (size_t f = 0; f < m->faces.size(); ++f) {
    auto& t = m->faces[f];
    const V mid = (m->vertices[t[0]] + m->vertices[t[1]] + m->vertices[t[2]]) / 3;
    if (m->FaceNormal(f).dot(mid - center) < 0) std::swap(t[1], t[2]);
  }
}

Mesh Icosahedron() {
  const double g = (1 + std::sqrt(5.0)) / 2;
  Mesh m;
  m.vertices = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  m.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  OrientOutward(&m);
  return m;
}

Mesh Octahedron(double radius) {
  Mesh mesh;
  for (int a = 0; a < 3; ++a) {
    mesh.vertices.push_back(radius * V::Unit(a));
    mesh.vertices.push_back(-radius * V::Unit(a));
  }
  for (int sx = 0; sx < 2; ++sx) {
    for (int sy = 0; sy < 2; ++sy) {
      for (int sz = 0; sz < 2; ++sz) {
        const int x = sx, y = 2 + sy, z = 4 + sz;
        if ((sx + sy + sz) % 2 == 0) {
          mesh.faces.push_back({x, y, z});
        } else {
          mesh.faces.push_back({x, z, y});
        }
      }
    }
  }
  return mesh;
}

Mesh Cube() {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  for (const auto& q : std::vector<std::array<int, 4>>{
           {0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}}) {
    m.faces.push_back({q[0], q[1], q[2]});
    m.faces.push_back({q[0], q[2], q[3]});
  }
  OrientOutward(&m);
  return m;
}

Mesh Corner(const V& apex, double s) {
  Mesh m;
  m.vertices = {apex, apex + V(s, 0, 0), apex + V(0, s, 0), apex + V(0, 0, s)};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  OrientOutward(&m);
  return m;
}

Mesh Append(Mesh a, const Mesh& b) {
  const auto base = static_cast<int32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto f : b.faces) a.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  return a;
}

Mesh ApexToApex(const V& apex) {
  Mesh m = Append(Corner(V(0, 0, 0), 1), Corner(V(0, 0, 0), -1));
  m.vertices[4] = apex;
  return m;
}

void OrientAwayFrom(Mesh* m, size_t f, const V& inside) {
  auto& t = m->faces[f];
  if (m->FaceNormal(f).dot(m->vertices[t[0]] - inside) < 0) std::swap(t[1], t[2]);
}

Mesh Bipyramid(double needle) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, needle, 0}, {0.7, 0.3, 1}, {0.7, 0.3, -1}};
  m.faces = {{3, 0, 1}, {3, 1, 2}, {3, 2, 0}, {4, 1, 0}, {4, 2, 1}, {4, 0, 2}};
  for (size_t f = 0; f < 6; ++f) {
    const int apex = f < 3 ? 3 : 4;
    OrientAwayFrom(&m, f, (m.vertices[0] + m.vertices[1] + m.vertices[2] + m.vertices[apex]) / 4);
  }
  return m;
}

Eigen::Matrix3d Rotation() {
  Eigen::Matrix3d r;
  r << 0.36, 0.48, -0.8, -0.8, 0.6, 0, 0.48, 0.64, 0.6;
  return r;
}

}  // namespace ms::test_meshes
