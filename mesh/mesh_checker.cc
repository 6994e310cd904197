#include "mesh/mesh_checker.h"

// CGAL stays in this file (exact predicates and box intersection).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>

#include "base/error.h"
#include "base/log.h"

namespace ms {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Segment = Kernel::Segment_3;

class DisjointSets {
 public:
  explicit DisjointSets(size_t n = 0) { Reset(n); }
  void Reset(size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  size_t Find(size_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  // Returns false if they were already joined.
  bool Union(size_t a, size_t b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return false;
    if (a < b) std::swap(a, b);
    parent_[a] = b;  // the smaller index is the root: deterministic
    return true;
  }

 private:
  std::vector<size_t> parent_;
};

// Union-find that also keeps, for each element, whether it is flipped relative to its root.
// Joining two faces across an edge states "same orientation" or "opposite"; a contradiction
// means the surface cannot be oriented.
class ParitySets {
 public:
  explicit ParitySets(size_t n) : parent_(n), parity_(n, 0) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  std::pair<size_t, uint8_t> Find(size_t x) {
    uint8_t parity = 0;
    size_t root = x;
    while (parent_[root] != root) {
      parity ^= parity_[root];
      root = parent_[root];
    }
    // Path compression with parities.
    uint8_t p = parity;
    while (parent_[x] != root) {
      const size_t next = parent_[x];
      const uint8_t next_parity = p ^ parity_[x];
      parent_[x] = root;
      parity_[x] = p;
      x = next;
      p = next_parity;
    }
    return {root, parity};
  }
  // relation: 0 = same orientation, 1 = one of them flipped. False on a contradiction.
  bool Join(size_t a, size_t b, uint8_t relation) {
    const auto [ra, pa] = Find(a);
    const auto [rb, pb] = Find(b);
    if (ra == rb) return (pa ^ pb) == relation;
    parent_[ra] = rb;
    parity_[ra] = pa ^ pb ^ relation;
    return true;
  }

 private:
  std::vector<size_t> parent_;
  std::vector<uint8_t> parity_;
};

enum FaceState : uint8_t {
  kTopological = 0,  // three distinct, valid indices
  kInvalid = 1,      // index out of range or a non-finite vertex: ignored by every check
  kRepeated = 2,     // a repeated index: degenerate, no edges
};

struct HalfEdge {
  int32_t lo, hi;  // undirected edge, lo < hi
  int64_t face;
  bool forward;  // the face goes lo -> hi
};

struct ComponentAccumulator {
  int64_t vertices = 0, edges = 0, faces = 0;
  int64_t boundary_edges = 0, non_manifold_edges = 0, non_manifold_vertices = 0;
  int64_t inconsistent_edges = 0, repeated_faces = 0;
  bool orientation_conflict = false;
  double volume6 = 0;  // six times the signed volume
};

template <typename T>
void AddExample(std::vector<T>* examples, const T& value, int max_examples) {
  if (static_cast<int>(examples->size()) < max_examples) examples->push_back(value);
}

// True if the two non-degenerate triangles meet anywhere other than in the vertices and edge
// they share by index (CGAL Polygon_mesh_processing's rule for self-intersections, applied to
// a triangle soup so that non-manifold input is handled too).
bool FacesIntersect(const std::array<int32_t, 3>& a, const std::array<int32_t, 3>& b,
                    const std::vector<Point>& p) {
  int shared = 0, ia = -1, ib = -1;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (a[i] == b[j]) {
        ++shared;
        ia = i;
        ib = j;
      }
    }
  }
  if (shared >= 3) return false;  // the same triangle: counted as a duplicate face instead
  if (shared == 2) {
    // They overlap only if coplanar and on the same side of the shared edge.
    int ra = 0, rb = 0;
    for (int i = 0; i < 3; ++i) {
      if (a[i] != b[0] && a[i] != b[1] && a[i] != b[2]) ra = a[i];
      if (b[i] != a[0] && b[i] != a[1] && b[i] != a[2]) rb = b[i];
    }
    int32_t s0 = -1, s1 = -1;
    for (int i = 0; i < 3; ++i) {
      if (a[i] != ra) (s0 < 0 ? s0 : s1) = a[i];
    }
    return CGAL::coplanar(p[s0], p[s1], p[ra], p[rb]) &&
           CGAL::coplanar_orientation(p[s0], p[s1], p[ra], p[rb]) == CGAL::POSITIVE;
  }
  const Triangle ta(p[a[0]], p[a[1]], p[a[2]]);
  const Triangle tb(p[b[0]], p[b[1]], p[b[2]]);
  if (shared == 1) {
    // Meeting elsewhere than the shared vertex means an opposite edge crosses the other face.
    const Segment sa(p[a[(ia + 1) % 3]], p[a[(ia + 2) % 3]]);
    const Segment sb(p[b[(ib + 1) % 3]], p[b[(ib + 2) % 3]]);
    return CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa);
  }
  return CGAL::do_intersect(ta, tb);
}

struct StopSearch {};

void FindSelfIntersections(const Mesh& mesh, const std::vector<Point>& points,
                           const std::vector<uint8_t>& state, const std::vector<uint8_t>& zero_area,
                           const MeshCheckOptions& options, MeshReport* report) {
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int64_t>;
  std::vector<Box> boxes;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (state[f] != kTopological || zero_area[f]) continue;
    const auto& t = mesh.faces[f];
    boxes.emplace_back(points[t[0]].bbox() + points[t[1]].bbox() + points[t[2]].bbox(),
                       static_cast<int64_t>(f));
  }
  const Timer timer;
  std::vector<std::array<int64_t, 2>> found;
  int64_t tested = 0;
  auto callback = [&](const Box& x, const Box& y) {
    ++tested;
    const int64_t f = x.info(), g = y.info();
    if (FacesIntersect(mesh.faces[f], mesh.faces[g], points)) {
      found.push_back({std::min(f, g), std::max(f, g)});
      if (static_cast<int64_t>(found.size()) >= options.max_self_intersections) throw StopSearch{};
    }
  };
  try {
    if (options.focus_faces.empty()) {
      CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), callback);
    } else {  // flagged faces against all; a pair of two flagged ones comes twice (deduplicated)
      std::vector<Box> focus;
      for (const Box& b : boxes) {
        if (options.focus_faces[b.info()]) focus.push_back(b);
      }
      CGAL::box_intersection_d(focus.begin(), focus.end(), boxes.begin(), boxes.end(),
                               [&](const Box& x, const Box& y) {
                                 if (x.info() != y.info()) callback(x, y);
                               });
    }
  } catch (const StopSearch&) {
    report->self_intersections_truncated = true;
  }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  report->num_self_intersections = static_cast<int64_t>(found.size());
  for (const auto& pair : found)
    AddExample(&report->self_intersection_examples, pair, options.max_examples);
  const double seconds = timer.Seconds();
  if (seconds > 1.0) {
    spdlog::info("self-intersections: {} faces, {} box pairs tested, {} intersecting in {:.1f} s",
                 boxes.size(), tested, found.size(), seconds);
  }
}

// Self-intersections among the pairs the float check's box search hands over
// (FloatRobustnessOptions::on_box_pair): the same pairs FindSelfIntersections finds with a search
// of its own, from one search instead of two.
class SharedSelfIntersectionSearch {
 public:
  SharedSelfIntersectionSearch(const Mesh& mesh, const std::vector<Point>& points,
                               const std::vector<uint8_t>& state,
                               const std::vector<uint8_t>& zero_area, int64_t max_pairs)
      : mesh_(mesh), points_(points), state_(state), zero_area_(zero_area), max_(max_pairs) {}

  void Test(int64_t f, int64_t g) {
    if (state_[f] != kTopological || zero_area_[f] || state_[g] != kTopological || zero_area_[g]) {
      return;
    }
    if (static_cast<int64_t>(found_.size()) >= max_) {
      truncated_ = true;
      return;
    }
    const auto &a = mesh_.faces[f], &b = mesh_.faces[g];
    const bool adjacent = std::any_of(
        a.begin(), a.end(), [&b](int32_t v) { return v == b[0] || v == b[1] || v == b[2]; });
    if (!adjacent && float_robustness_internal::TrianglesSurelyApart(Corners(a), Corners(b), 0)) {
      return;
    }
    if (FacesIntersect(a, b, points_)) found_.push_back({f, g});
  }

  float_robustness_internal::Triangle Corners(const std::array<int32_t, 3>& face) const {
    return {mesh_.vertices[face[0]], mesh_.vertices[face[1]], mesh_.vertices[face[2]]};
  }

  void Report(int max_examples, MeshReport* report) {
    std::sort(found_.begin(), found_.end());
    found_.erase(std::unique(found_.begin(), found_.end()), found_.end());
    report->self_intersections_truncated = truncated_;
    report->num_self_intersections = static_cast<int64_t>(found_.size());
    for (const auto& pair : found_) {
      AddExample(&report->self_intersection_examples, pair, max_examples);
    }
  }

 private:
  const Mesh& mesh_;
  const std::vector<Point>& points_;
  const std::vector<uint8_t>& state_;
  const std::vector<uint8_t>& zero_area_;
  int64_t max_;
  std::vector<std::array<int64_t, 2>> found_;
  bool truncated_ = false;
};

std::string FormatEdges(const std::vector<std::array<int32_t, 2>>& edges) {
  std::string s;
  for (const auto& e : edges) s += fmt::format("{}{}-{}", s.empty() ? "" : " ", e[0], e[1]);
  return s;
}

template <typename T>
std::string FormatList(const std::vector<T>& values) {
  return fmt::format("{}", fmt::join(values, " "));
}

std::string FormatPairs(const std::vector<std::array<int64_t, 2>>& pairs) {
  std::string s;
  for (const auto& p : pairs) s += fmt::format("{}({},{})", s.empty() ? "" : " ", p[0], p[1]);
  return s;
}

FloatRobustnessOptions FloatOptions(const MeshCheckOptions& options) {
  FloatRobustnessOptions f;
  f.relative_tolerance = options.float_tolerance;
  f.absolute_tolerance = options.float_tolerance_abs;
  f.check_face_pairs = options.check_self_intersections;
  f.max_examples = options.max_examples;
  f.max_pairs = options.max_self_intersections;
  f.focus_faces = options.focus_faces;
  f.candidates = options.candidates;
  return f;
}

// "1.2e-07 (3.4e-08 of the diagonal)".
std::string WithRelative(double value, double diagonal) {
  return diagonal > 0 ? fmt::format("{:.3g} ({:.2g} of the diagonal)", value, value / diagonal)
                      : fmt::format("{:.3g}", value);
}

// What CheckMesh's steps share: the faces' states and the vertices they reference.
struct FaceTable {
  std::vector<Point> points;        // the vertices, for exact predicates
  std::vector<uint8_t> state;       // FaceState per face
  std::vector<uint8_t> zero_area;   // per face: three distinct but collinear corners
  std::vector<uint8_t> referenced;  // per vertex: in a valid face
};

// Faces: validity, degeneracy (exact), references.
FaceTable ClassifyFaces(const Mesh& mesh, int max_ex, MeshReport* r) {
  const auto nv = static_cast<int64_t>(mesh.vertices.size());
  const auto nf = static_cast<int64_t>(mesh.faces.size());
  FaceTable t;
  t.points.resize(nv);
  std::vector<uint8_t> finite(nv);
  for (int64_t v = 0; v < nv; ++v) {
    const Eigen::Vector3d& x = mesh.vertices[v];
    finite[v] = x.allFinite();
    t.points[v] = Point(x.x(), x.y(), x.z());
  }
  t.state.assign(nf, kTopological);
  t.zero_area.assign(nf, 0);
  t.referenced.assign(nv, 0);
  for (int64_t f = 0; f < nf; ++f) {
    const auto& face = mesh.faces[f];
    bool ok = true;
    for (int32_t v : face) ok = ok && v >= 0 && v < nv && finite[v];
    if (!ok) {
      t.state[f] = kInvalid;
      ++r->num_invalid_faces;
      AddExample(&r->invalid_face_examples, f, max_ex);
      continue;
    }
    for (int32_t v : face) t.referenced[v] = 1;
    if (face[0] == face[1] || face[1] == face[2] || face[0] == face[2]) {
      t.state[f] = kRepeated;
    } else if (CGAL::collinear(t.points[face[0]], t.points[face[1]], t.points[face[2]])) {
      t.zero_area[f] = 1;
    }
    if (t.state[f] == kRepeated || t.zero_area[f]) {
      ++r->num_degenerate_faces;
      AddExample(&r->degenerate_face_examples, f, max_ex);
    }
  }
  for (int64_t v = 0; v < nv; ++v) {
    if (!t.referenced[v]) {
      ++r->num_unreferenced_vertices;
      AddExample(&r->unreferenced_vertex_examples, static_cast<int32_t>(v), max_ex);
    }
  }
  return t;
}

// Duplicate faces: the same vertex set (either orientation).
void CountDuplicateFaces(const Mesh& mesh, const FaceTable& t, int max_ex, MeshReport* r) {
  std::vector<std::pair<std::array<int32_t, 3>, int64_t>> keys;
  keys.reserve(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (t.state[f] != kTopological) continue;
    std::array<int32_t, 3> k = mesh.faces[f];
    std::sort(k.begin(), k.end());
    keys.emplace_back(k, static_cast<int64_t>(f));
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int64_t> duplicates;
  for (size_t i = 1; i < keys.size(); ++i) {
    if (keys[i].first == keys[i - 1].first) duplicates.push_back(keys[i].second);
  }
  std::sort(duplicates.begin(), duplicates.end());
  r->num_duplicate_faces = static_cast<int64_t>(duplicates.size());
  for (int64_t f : duplicates) AddExample(&r->duplicate_face_examples, f, max_ex);
}

// Components: vertices joined by valid faces. Returns each referenced vertex's component, ids
// compact in the order of their smallest vertex (-1 for unreferenced vertices).
std::vector<int64_t> LabelComponents(const Mesh& mesh, const FaceTable& t,
                                     int64_t* num_components) {
  const auto nv = static_cast<int64_t>(mesh.vertices.size());
  DisjointSets vertex_sets(nv);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (t.state[f] == kInvalid) continue;
    const auto& face = mesh.faces[f];
    vertex_sets.Union(face[0], face[1]);
    vertex_sets.Union(face[1], face[2]);
  }
  std::vector<int64_t> component_of(nv, -1);
  *num_components = 0;
  for (int64_t v = 0; v < nv; ++v) {
    if (!t.referenced[v]) continue;
    const size_t root = vertex_sets.Find(v);
    if (component_of[root] < 0) component_of[root] = (*num_components)++;
    component_of[v] = component_of[root];
  }
  return component_of;
}

// Edges: boundary, non-manifold, orientation.
void CheckEdges(const Mesh& mesh, const FaceTable& t, const std::vector<int64_t>& component_of,
                int max_ex, std::vector<ComponentAccumulator>* acc, MeshReport* r) {
  const auto nf = static_cast<int64_t>(mesh.faces.size());
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * nf);
  for (int64_t f = 0; f < nf; ++f) {
    if (t.state[f] != kTopological) continue;
    const auto& face = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      const int32_t a = face[k], b = face[(k + 1) % 3];
      half_edges.push_back({std::min(a, b), std::max(a, b), f, a < b});
    }
  }
  std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.lo, x.hi, x.face) < std::tie(y.lo, y.hi, y.face);
  });
  ParitySets orientation(nf);
  for (size_t i = 0; i < half_edges.size();) {
    size_t j = i;
    while (j < half_edges.size() && half_edges[j].lo == half_edges[i].lo &&
           half_edges[j].hi == half_edges[i].hi) {
      ++j;
    }
    const std::array<int32_t, 2> edge{half_edges[i].lo, half_edges[i].hi};
    ComponentAccumulator& c = (*acc)[component_of[edge[0]]];
    ++r->num_edges;
    ++c.edges;
    const size_t count = j - i;
    if (count == 1) {
      ++r->num_boundary_edges;
      ++c.boundary_edges;
      AddExample(&r->boundary_edge_examples, edge, max_ex);
    } else if (count >= 3) {
      ++r->num_non_manifold_edges;
      ++c.non_manifold_edges;
      AddExample(&r->non_manifold_edge_examples, edge, max_ex);
    } else {
      const bool same_direction = half_edges[i].forward == half_edges[i + 1].forward;
      if (same_direction) {
        ++r->num_inconsistent_edges;
        ++c.inconsistent_edges;
        AddExample(&r->inconsistent_edge_examples, edge, max_ex);
      }
      if (!orientation.Join(half_edges[i].face, half_edges[i + 1].face, same_direction ? 1 : 0)) {
        c.orientation_conflict = true;
      }
    }
    i = j;
  }
}

// Vertices: the edges opposite to v must form one cycle (or one path on a boundary).
void CheckVertexLinks(const Mesh& mesh, const FaceTable& t,
                      const std::vector<int64_t>& component_of, int max_ex,
                      std::vector<ComponentAccumulator>* acc, MeshReport* r) {
  const auto nv = static_cast<int64_t>(mesh.vertices.size());
  const auto nf = static_cast<int64_t>(mesh.faces.size());
  std::vector<int64_t> offsets(nv + 1, 0);
  for (int64_t f = 0; f < nf; ++f) {
    if (t.state[f] != kTopological) continue;
    for (int32_t v : mesh.faces[f]) ++offsets[v + 1];
  }
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<int64_t> incident(offsets[nv]);
  std::vector<int64_t> fill(offsets.begin(), offsets.end() - 1);
  for (int64_t f = 0; f < nf; ++f) {
    if (t.state[f] != kTopological) continue;
    for (int32_t v : mesh.faces[f]) incident[fill[v]++] = f;
  }
  std::vector<int32_t> nodes;
  std::vector<std::array<int32_t, 2>> link;
  std::vector<int> degree;
  DisjointSets link_sets;  // reused: one per vertex would allocate a million times
  for (int64_t v = 0; v < nv; ++v) {
    const int64_t begin = offsets[v], end = offsets[v + 1];
    if (begin == end) continue;
    ComponentAccumulator& c = (*acc)[component_of[v]];
    ++c.vertices;
    nodes.clear();
    link.clear();
    for (int64_t k = begin; k < end; ++k) {
      const auto& face = mesh.faces[incident[k]];
      const int i = face[0] == v ? 0 : (face[1] == v ? 1 : 2);
      link.push_back({face[(i + 1) % 3], face[(i + 2) % 3]});
      nodes.push_back(face[(i + 1) % 3]);
      nodes.push_back(face[(i + 2) % 3]);
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    degree.assign(nodes.size(), 0);
    link_sets.Reset(nodes.size());
    size_t link_components = nodes.size();
    for (const auto& e : link) {
      const size_t a = std::lower_bound(nodes.begin(), nodes.end(), e[0]) - nodes.begin();
      const size_t b = std::lower_bound(nodes.begin(), nodes.end(), e[1]) - nodes.begin();
      ++degree[a];
      ++degree[b];
      if (link_sets.Union(a, b)) --link_components;
    }
    int ends = 0;
    bool regular = link_components == 1;
    for (int d : degree) {
      if (d == 1) {
        ++ends;
      } else if (d != 2) {
        regular = false;
      }
    }
    if (regular && ends == 2) {
      ++r->num_boundary_vertices;
    } else if (!regular || ends != 0) {
      ++r->num_non_manifold_vertices;
      ++c.non_manifold_vertices;
      AddExample(&r->non_manifold_vertex_examples, static_cast<int32_t>(v), max_ex);
    }
  }
}

// Per-component topology and volume (relative to the box centre), largest component first.
void SummarizeComponents(const Mesh& mesh, const FaceTable& t,
                         const std::vector<int64_t>& component_of,
                         std::vector<ComponentAccumulator>* acc, MeshReport* r) {
  const auto nv = static_cast<int64_t>(mesh.vertices.size());
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  if (nv > 0) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (int64_t v = 0; v < nv; ++v) {
      if (!t.referenced[v]) continue;
      lo = lo.cwiseMin(mesh.vertices[v]);
      hi = hi.cwiseMax(mesh.vertices[v]);
    }
    if (lo.allFinite() && hi.allFinite()) origin = 0.5 * (lo + hi);
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (t.state[f] != kTopological) continue;
    const auto& face = mesh.faces[f];
    const Eigen::Vector3d a = mesh.vertices[face[0]] - origin, b = mesh.vertices[face[1]] - origin,
                          c = mesh.vertices[face[2]] - origin;
    (*acc)[component_of[face[0]]].volume6 += a.dot(b.cross(c));
  }
  r->num_components = static_cast<int64_t>(acc->size());
  bool all_have_genus = !acc->empty();
  int64_t genus_sum = 0;
  for (const ComponentAccumulator& c : *acc) {
    MeshComponent out;
    out.num_vertices = c.vertices;
    out.num_edges = c.edges;
    out.num_faces = c.faces;
    out.euler_characteristic = c.vertices - c.edges + c.faces;
    out.closed = c.boundary_edges == 0;
    out.manifold = c.non_manifold_edges == 0 && c.non_manifold_vertices == 0 &&
                   c.repeated_faces == 0 && c.faces > 0;
    out.oriented = out.manifold && c.inconsistent_edges == 0;
    out.orientable = out.manifold && !c.orientation_conflict;
    if (out.closed && out.manifold && out.orientable) {
      out.genus = (2 - out.euler_characteristic) / 2;
      genus_sum += *out.genus;
    } else {
      all_have_genus = false;
    }
    if (out.closed && out.oriented) out.signed_volume = c.volume6 / 6.0;
    r->euler_characteristic += out.euler_characteristic;
    r->components.push_back(out);
  }
  if (all_have_genus) r->genus = genus_sum;
  std::stable_sort(
      r->components.begin(), r->components.end(),
      [](const MeshComponent& a, const MeshComponent& b) { return a.num_faces > b.num_faces; });
}

// The verdicts from the counts.
void DecideValidity(const MeshCheckOptions& options, MeshReport* r) {
  r->allow_float_issues = options.allow_float_issues;
  r->is_float_robust = r->float_robustness.IsRobust();
  const bool common = r->num_faces > 0 && r->num_invalid_faces == 0 &&
                      r->num_non_manifold_edges == 0 && r->num_non_manifold_vertices == 0 &&
                      r->num_inconsistent_edges == 0 && r->num_degenerate_faces == 0 &&
                      r->num_duplicate_faces == 0 && r->num_self_intersections == 0;
  r->is_closed_manifold = common && r->num_boundary_edges == 0 && r->num_boundary_vertices == 0;
  r->is_valid = (options.allow_boundary ? common : r->is_closed_manifold) &&
                (r->is_float_robust || options.allow_float_issues);
}

}  // namespace

void MeshCheckOptions::Check() const {
  if (max_examples < 0) throw InputError("mesh check: max_examples must be >= 0");
  if (max_self_intersections < 1) {
    throw InputError("mesh check: max_self_intersections must be >= 1");
  }
  FloatOptions(*this).Check();
}

MeshReport CheckMesh(const Mesh& mesh, const MeshCheckOptions& options) {
  options.Check();
  if (!options.focus_faces.empty() && options.focus_faces.size() != mesh.faces.size()) {
    throw InputError(fmt::format("mesh check: {} focus flags for {} faces",
                                 options.focus_faces.size(), mesh.faces.size()));
  }
  const int max_ex = options.max_examples;
  MeshReport r;
  r.allow_boundary = options.allow_boundary;
  r.num_vertices = static_cast<int64_t>(mesh.vertices.size());
  r.num_faces = static_cast<int64_t>(mesh.faces.size());
  const FaceTable faces = ClassifyFaces(mesh, max_ex, &r);
  if (options.check_topology) {
    CountDuplicateFaces(mesh, faces, max_ex, &r);
    int64_t num_components = 0;
    const std::vector<int64_t> component_of = LabelComponents(mesh, faces, &num_components);
    std::vector<ComponentAccumulator> acc(num_components);
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      if (faces.state[f] == kTopological) ++acc[component_of[mesh.faces[f][0]]].faces;
      if (faces.state[f] == kRepeated) ++acc[component_of[mesh.faces[f][0]]].repeated_faces;
    }
    CheckEdges(mesh, faces, component_of, max_ex, &acc, &r);
    CheckVertexLinks(mesh, faces, component_of, max_ex, &acc, &r);
    SummarizeComponents(mesh, faces, component_of, &acc, &r);
  }
  // Floating point (mesh/float_robustness.h), whose box search also hands the exact
  // self-intersection test its candidate pairs.
  r.self_intersections_checked = options.check_self_intersections;
  std::vector<uint8_t> usable(mesh.faces.size());
  for (size_t f = 0; f < usable.size(); ++f) usable[f] = faces.state[f] != kInvalid;
  SharedSelfIntersectionSearch exact(mesh, faces.points, faces.state, faces.zero_area,
                                     options.max_self_intersections);
  FloatRobustnessOptions float_options = FloatOptions(options);
  if (options.check_self_intersections) {
    float_options.on_box_pair = [&exact](int64_t f, int64_t g) { exact.Test(f, g); };
  }
  r.float_robustness = CheckFloatRobustness(mesh, usable, float_options);
  if (options.check_self_intersections) {
    const FloatRobustnessReport& fr = r.float_robustness;
    if (fr.close_face_pairs_truncated && fr.float_intersections_truncated) {
      // The shared search stopped early: a search of the exact test's own.
      FindSelfIntersections(mesh, faces.points, faces.state, faces.zero_area, options, &r);
    } else {
      exact.Report(options.max_examples, &r);
    }
  }
  DecideValidity(options, &r);
  return r;
}

std::vector<std::string> MeshReport::Problems() const {
  std::vector<std::string> p;
  if (num_faces == 0) p.push_back("the mesh has no faces");
  if (num_invalid_faces > 0) {
    p.push_back(fmt::format("{} faces with an index out of range or a non-finite vertex (e.g. {})",
                            num_invalid_faces, FormatList(invalid_face_examples)));
  }
  if (num_boundary_edges > 0 && !allow_boundary) {
    p.push_back(fmt::format(
        "{} boundary edges (e.g. {}) and {} vertices whose fan is open: the surface is not closed",
        num_boundary_edges, FormatEdges(boundary_edge_examples), num_boundary_vertices));
  }
  if (num_non_manifold_edges > 0) {
    p.push_back(fmt::format("{} non-manifold edges in 3 or more faces (e.g. {})",
                            num_non_manifold_edges, FormatEdges(non_manifold_edge_examples)));
  }
  if (num_non_manifold_vertices > 0) {
    p.push_back(fmt::format(
        "{} non-manifold vertices whose opposite edges are not one cycle or path (e.g. {})",
        num_non_manifold_vertices, FormatList(non_manifold_vertex_examples)));
  }
  if (num_inconsistent_edges > 0) {
    p.push_back(
        fmt::format("{} edges traversed twice in the same direction (e.g. {}): "
                    "inconsistent orientation",
                    num_inconsistent_edges, FormatEdges(inconsistent_edge_examples)));
  }
  if (num_degenerate_faces > 0) {
    p.push_back(fmt::format("{} degenerate faces with a repeated vertex or zero area (e.g. {})",
                            num_degenerate_faces, FormatList(degenerate_face_examples)));
  }
  if (num_duplicate_faces > 0) {
    p.push_back(fmt::format("{} duplicate faces (e.g. {})", num_duplicate_faces,
                            FormatList(duplicate_face_examples)));
  }
  if (num_self_intersections > 0) {
    p.push_back(fmt::format("{}{} pairs of self-intersecting faces (e.g. {})",
                            self_intersections_truncated ? "at least " : "", num_self_intersections,
                            FormatPairs(self_intersection_examples)));
  }
  if (!allow_float_issues) {
    const FloatRobustnessReport& fr = float_robustness;
    const std::string tolerance = WithRelative(fr.tolerance, fr.diagonal);
    if (fr.num_near_vertex_pairs > 0) {
      p.push_back(fmt::format(
          "{}{} pairs of distinct vertices at most {} apart (e.g. {}): near-coincident in "
          "floating point",
          fr.near_vertex_pairs_truncated ? "at least " : "", fr.num_near_vertex_pairs, tolerance,
          FormatEdges(fr.near_vertex_examples)));
    }
    if (fr.num_close_face_pairs > 0) {
      p.push_back(fmt::format("{}{} pairs of faces sharing no vertex at most {} apart (e.g. {})",
                              fr.close_face_pairs_truncated ? "at least " : "",
                              fr.num_close_face_pairs, tolerance,
                              FormatPairs(fr.close_face_pair_examples)));
    }
    if (fr.num_float_intersections > 0) {
      p.push_back(fmt::format(
          "{}{} pairs of faces sharing no vertex intersect in double precision (Moller's test, "
          "as Open3D's get_self_intersecting_triangles) (e.g. {})",
          fr.float_intersections_truncated ? "at least " : "", fr.num_float_intersections,
          FormatPairs(fr.float_intersection_examples)));
    }
  }
  return p;
}

std::string MeshReport::ToTable(const std::string& source) const {
  std::string out;
  auto row = [&out](const char* label, const std::string& value, const std::string& examples = "") {
    fmt::format_to(std::back_inserter(out), "  {:<28}{:>12}{}{}\n", label, value,
                   examples.empty() ? "" : "   e.g. ", examples);
  };
  auto count = [&row](const char* label, int64_t n, const std::string& examples) {
    row(label, std::to_string(n), n > 0 ? examples : "");
  };
  out += source.empty() ? "mesh check\n" : fmt::format("mesh check: {}\n", source);
  row("vertices", std::to_string(num_vertices));
  row("faces", std::to_string(num_faces));
  row("edges", std::to_string(num_edges));
  row("connected components", std::to_string(num_components));
  row("Euler characteristic", std::to_string(euler_characteristic));
  row("genus", genus ? std::to_string(*genus) : "-");
  count("boundary edges", num_boundary_edges, FormatEdges(boundary_edge_examples));
  row("boundary vertices", std::to_string(num_boundary_vertices));
  count("non-manifold edges", num_non_manifold_edges, FormatEdges(non_manifold_edge_examples));
  count("non-manifold vertices", num_non_manifold_vertices,
        FormatList(non_manifold_vertex_examples));
  count("inconsistent edges", num_inconsistent_edges, FormatEdges(inconsistent_edge_examples));
  count("degenerate faces", num_degenerate_faces, FormatList(degenerate_face_examples));
  count("duplicate faces", num_duplicate_faces, FormatList(duplicate_face_examples));
  count("invalid faces", num_invalid_faces, FormatList(invalid_face_examples));
  count("unreferenced vertices", num_unreferenced_vertices,
        FormatList(unreferenced_vertex_examples));
  if (self_intersections_checked) {
    count("self-intersecting pairs", num_self_intersections,
          (self_intersections_truncated ? "(search stopped) " : "") +
              FormatPairs(self_intersection_examples));
  } else {
    row("self-intersecting pairs", "not checked");
  }
  // Floating-point robustness: the values, then the counts that decide validity.
  const FloatRobustnessReport& fr = float_robustness;
  auto note = [&out](const char* label, const std::string& value, const std::string& text) {
    fmt::format_to(std::back_inserter(out), "  {:<28}{:>12}{}{}\n", label, value,
                   text.empty() ? "" : "   ", text);
  };
  out += "  floating point (double precision):\n";
  note("bounding-box diagonal", fmt::format("{:.6g}", fr.diagonal), "");
  note("float tolerance", fmt::format("{:.3g}", fr.tolerance),
       fr.diagonal > 0 ? fmt::format("{:.2g} of the diagonal", fr.relative_tolerance) : "");
  if (fr.shortest_edge) {
    note("shortest edge", fmt::format("{:.3g}", *fr.shortest_edge),
         fmt::format("{}edge {}-{} of face {}",
                     fr.diagonal > 0
                         ? fmt::format("{:.2g} of the diagonal; ", *fr.shortest_edge / fr.diagonal)
                         : "",
                     fr.shortest_edge_vertices[0], fr.shortest_edge_vertices[1],
                     fr.shortest_edge_face));
    note("smallest angle (degrees)", fmt::format("{:.3g}", *fr.smallest_angle_degrees),
         fmt::format("face {} at vertex {}", fr.smallest_angle_face, fr.smallest_angle_vertex));
  } else {
    row("shortest edge", "-");
    row("smallest angle (degrees)", "-");
  }
  count("near-coincident vertices", fr.num_near_vertex_pairs,
        (fr.near_vertex_pairs_truncated ? "(search stopped) " : "") +
            FormatEdges(fr.near_vertex_examples));
  if (fr.face_pairs_checked) {
    count("close face pairs", fr.num_close_face_pairs,
          (fr.close_face_pairs_truncated ? "(search stopped) " : "") +
              FormatPairs(fr.close_face_pair_examples));
    count("float self-intersections", fr.num_float_intersections,
          (fr.float_intersections_truncated ? "(search stopped) " : "") +
              FormatPairs(fr.float_intersection_examples));
  } else {
    row("close face pairs", "not checked");
    row("float self-intersections", "not checked");
  }
  if (components.size() > 1) {
    out += "  components (largest first):\n";
    fmt::format_to(std::back_inserter(out), "    {:>10} {:>10} {:>8} {:>7} {:>8} {:>8} {:>6}\n",
                   "faces", "vertices", "chi", "closed", "manifold", "oriented", "genus");
    const size_t shown = std::min<size_t>(components.size(), 20);
    for (size_t i = 0; i < shown; ++i) {
      const MeshComponent& c = components[i];
      fmt::format_to(std::back_inserter(out), "    {:>10} {:>10} {:>8} {:>7} {:>8} {:>8} {:>6}\n",
                     c.num_faces, c.num_vertices, c.euler_characteristic, c.closed ? "yes" : "no",
                     c.manifold ? "yes" : "no", c.oriented ? "yes" : "no",
                     c.genus ? std::to_string(*c.genus) : "-");
    }
    if (shown < components.size()) {
      fmt::format_to(std::back_inserter(out), "    ... {} more\n", components.size() - shown);
    }
  }
  if (is_valid) {
    out += is_closed_manifold ? "result: VALID closed 2-manifold"
                              : "result: VALID 2-manifold with boundary";
    out += is_float_robust ? "\n" : " (floating-point issues allowed, see above)\n";
  } else {
    out += "result: NOT VALID\n";
    for (const std::string& p : Problems()) out += "  - " + p + "\n";
  }
  return out;
}

std::string MeshReport::ToJson(const std::string& source) const {
  using nlohmann::json;
  auto edges = [](const std::vector<std::array<int32_t, 2>>& e) {
    json a = json::array();
    for (const auto& x : e) a.push_back({x[0], x[1]});
    return a;
  };
  json j;
  if (!source.empty()) j["source"] = source;
  j["valid"] = is_valid;
  j["closed_manifold"] = is_closed_manifold;
  j["allow_boundary"] = allow_boundary;
  j["vertices"] = num_vertices;
  j["faces"] = num_faces;
  j["edges"] = num_edges;
  j["components"] = num_components;
  j["euler_characteristic"] = euler_characteristic;
  j["genus"] = genus ? json(*genus) : json(nullptr);
  j["boundary_edges"] = num_boundary_edges;
  j["boundary_vertices"] = num_boundary_vertices;
  j["non_manifold_edges"] = num_non_manifold_edges;
  j["non_manifold_vertices"] = num_non_manifold_vertices;
  j["inconsistent_edges"] = num_inconsistent_edges;
  j["degenerate_faces"] = num_degenerate_faces;
  j["duplicate_faces"] = num_duplicate_faces;
  j["invalid_faces"] = num_invalid_faces;
  j["unreferenced_vertices"] = num_unreferenced_vertices;
  j["self_intersections_checked"] = self_intersections_checked;
  if (self_intersections_checked) {
    j["self_intersections"] = num_self_intersections;
    j["self_intersections_truncated"] = self_intersections_truncated;
  } else {
    j["self_intersections"] = nullptr;
  }
  json ex;
  ex["boundary_edges"] = edges(boundary_edge_examples);
  ex["non_manifold_edges"] = edges(non_manifold_edge_examples);
  ex["inconsistent_edges"] = edges(inconsistent_edge_examples);
  ex["non_manifold_vertices"] = non_manifold_vertex_examples;
  ex["unreferenced_vertices"] = unreferenced_vertex_examples;
  ex["invalid_faces"] = invalid_face_examples;
  ex["degenerate_faces"] = degenerate_face_examples;
  ex["duplicate_faces"] = duplicate_face_examples;
  json pairs = json::array();
  for (const auto& p : self_intersection_examples) pairs.push_back({p[0], p[1]});
  ex["self_intersections"] = pairs;
  j["examples"] = ex;
  j["float_robust"] = is_float_robust;
  j["allow_float_issues"] = allow_float_issues;
  {
    const FloatRobustnessReport& fr = float_robustness;
    auto optional = [](const std::optional<double>& x) { return x ? json(*x) : json(nullptr); };
    auto pair_list = [](const std::vector<std::array<int64_t, 2>>& list) {
      json a = json::array();
      for (const auto& p : list) a.push_back({p[0], p[1]});
      return a;
    };
    json f;
    f["diagonal"] = fr.diagonal;
    f["tolerance"] = fr.tolerance;
    f["relative_tolerance"] = fr.relative_tolerance;
    f["shortest_edge"] = optional(fr.shortest_edge);
    f["shortest_edge_relative"] =
        fr.shortest_edge && fr.diagonal > 0 ? json(*fr.shortest_edge / fr.diagonal) : json(nullptr);
    f["shortest_edge_vertices"] =
        fr.shortest_edge ? json({fr.shortest_edge_vertices[0], fr.shortest_edge_vertices[1]})
                         : json(nullptr);
    f["shortest_edge_face"] = fr.shortest_edge ? json(fr.shortest_edge_face) : json(nullptr);
    f["smallest_angle_degrees"] = optional(fr.smallest_angle_degrees);
    f["smallest_angle_face"] =
        fr.smallest_angle_degrees ? json(fr.smallest_angle_face) : json(nullptr);
    f["smallest_angle_vertex"] =
        fr.smallest_angle_degrees ? json(fr.smallest_angle_vertex) : json(nullptr);
    f["near_vertex_pairs"] = fr.num_near_vertex_pairs;
    f["near_vertex_pairs_truncated"] = fr.near_vertex_pairs_truncated;
    f["closest_vertex_distance"] = optional(fr.closest_vertex_distance);
    f["face_pairs_checked"] = fr.face_pairs_checked;
    if (fr.face_pairs_checked) {
      f["close_face_pairs"] = fr.num_close_face_pairs;
      f["close_face_pairs_truncated"] = fr.close_face_pairs_truncated;
      f["closest_face_pair_distance"] = optional(fr.closest_face_pair_distance);
      f["float_intersections"] = fr.num_float_intersections;
      f["float_intersections_truncated"] = fr.float_intersections_truncated;
    } else {
      f["close_face_pairs"] = nullptr;
      f["float_intersections"] = nullptr;
    }
    json fex;
    fex["near_vertex_pairs"] = edges(fr.near_vertex_examples);
    fex["close_face_pairs"] = pair_list(fr.close_face_pair_examples);
    fex["float_intersections"] = pair_list(fr.float_intersection_examples);
    f["examples"] = fex;
    j["float_robustness"] = f;
  }
  json comps = json::array();
  constexpr size_t kMaxListed = 1000;
  for (size_t i = 0; i < std::min(components.size(), kMaxListed); ++i) {
    const MeshComponent& c = components[i];
    json o;
    o["faces"] = c.num_faces;
    o["vertices"] = c.num_vertices;
    o["edges"] = c.num_edges;
    o["euler_characteristic"] = c.euler_characteristic;
    o["closed"] = c.closed;
    o["manifold"] = c.manifold;
    o["oriented"] = c.oriented;
    o["orientable"] = c.orientable;
    o["genus"] = c.genus ? json(*c.genus) : json(nullptr);
    o["signed_volume"] = c.signed_volume ? json(*c.signed_volume) : json(nullptr);
    comps.push_back(o);
  }
  j["component_list"] = comps;
  j["problems"] = Problems();
  return j.dump(2) + "\n";
}

}  // namespace ms
