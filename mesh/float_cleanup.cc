#include "mesh/float_cleanup.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <unordered_map>
#include <utility>

#include "base/check.h"
#include "base/log.h"
#include "base/memory.h"
#include "mesh/face_tree.h"
#include "mesh/float_robustness.h"

namespace ms {
namespace {

using Eigen::Vector3d;
using float_robustness_internal::SegmentCrossesTriangle;
using float_robustness_internal::Triangle;
using float_robustness_internal::TriangleClosestPoints;
using float_robustness_internal::TriangleDistance;
using float_robustness_internal::TrianglesIntersectLikeOpen3d;
using Face = std::array<int32_t, 3>;

struct Box3 {
  Vector3d lo = Vector3d::Constant(INFINITY), hi = Vector3d::Constant(-INFINITY);
  void Add(const Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void Add(const Box3& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  Box3 Grown(double d) const { return {lo.array() - d, hi.array() + d}; }
  bool Overlaps(const Box3& b) const {
    return (lo.array() <= b.hi.array()).all() && (b.lo.array() <= hi.array()).all();
  }
};

FloatBox3 AroundBox(const Box3& b) { return FloatBox3::Around(b.lo, b.hi); }

// The problems a check found, every pair listed, sorted (as CheckFloatRobustness sorts them).
struct ProblemPairs {
  std::vector<std::array<int32_t, 2>> near_vertices;
  std::vector<std::array<int64_t, 2>> close_faces, crossing_faces;
  bool complete = true;  // false: a list stopped at the check's max_pairs

  int64_t Count() const {
    return static_cast<int64_t>(near_vertices.size() + close_faces.size() + crossing_faces.size());
  }
};

template <typename T>
void SortUnique(std::vector<T>* v) {
  std::sort(v->begin(), v->end());
  v->erase(std::unique(v->begin(), v->end()), v->end());
}

// Each vertex's alive faces, in the order one vector per vertex would keep them (faces appended,
// a removal closing its gap), since the collapses depend on that order. One array holds every
// vertex's initial faces, with the room they took; a list that outgrows its room, and those of
// vertices made later, move to vectors of their own. At 10^6 vertices a vector per vertex took
// about 72 bytes a vertex, this about 36.
class VertexFaceLists {
 public:
  struct List {
    const int32_t *first, *last;
    const int32_t* begin() const { return first; }
    const int32_t* end() const { return last; }
    bool empty() const { return first == last; }
  };

  VertexFaceLists(const std::vector<Face>& faces, size_t vertices)
      : start_(vertices + 1, 0), count_(vertices, 0) {
    MS_CHECK(3 * faces.size() <= UINT32_MAX) << "too many faces for the cleanup";
    for (const Face& face : faces) {
      for (int32_t v : face) ++start_[v + 1];
    }
    for (size_t v = 0; v < vertices; ++v) start_[v + 1] += start_[v];
    faces_.resize(start_.back());
    for (size_t f = 0; f < faces.size(); ++f) {
      for (int32_t v : faces[f]) faces_[start_[v] + count_[v]++] = static_cast<int32_t>(f);
    }
  }

  size_t size() const { return count_.size(); }

  List operator[](int32_t v) const {
    const auto moved = moved_.find(v);
    if (moved != moved_.end()) {
      return {moved->second.data(), moved->second.data() + moved->second.size()};
    }
    const int32_t* first = faces_.data() + start_[v];
    return {first, first + count_[v]};
  }

  void Add(int32_t v, int32_t f) {
    auto moved = moved_.find(v);
    if (moved == moved_.end()) {
      if (start_[v] + count_[v] < start_[v + 1]) {
        faces_[start_[v] + count_[v]++] = f;
        return;
      }
      const int32_t* first = faces_.data() + start_[v];
      moved = moved_.emplace(v, std::vector<int32_t>(first, first + count_[v])).first;
      count_[v] = 0;
    }
    moved->second.push_back(f);
  }

  // Removes every occurrence of f from v's list.
  void Remove(int32_t v, int32_t f) {
    const auto moved = moved_.find(v);
    if (moved != moved_.end()) {
      auto& list = moved->second;
      list.erase(std::remove(list.begin(), list.end(), f), list.end());
      return;
    }
    int32_t* first = faces_.data() + start_[v];
    count_[v] = static_cast<uint32_t>(std::remove(first, first + count_[v], f) - first);
  }

  void Clear(int32_t v) {
    const auto moved = moved_.find(v);
    if (moved != moved_.end()) moved->second.clear();
    count_[v] = 0;
  }

  // A new vertex, with no room of its own.
  void AddVertex() {
    start_.push_back(start_.back());
    count_.push_back(0);
  }

 private:
  std::vector<uint32_t> start_;  // room of vertex v: faces_[start_[v], start_[v + 1])
  std::vector<uint32_t> count_;  // faces in the room
  std::vector<int32_t> faces_;
  std::unordered_map<int32_t, std::vector<int32_t>> moved_;  // lists out of their room
};

// The mesh under local edits, round after round: faces are never changed in place, only killed
// and appended, so face and vertex indices hold from round to round (the mesh is compacted once,
// at the end), and a tree built over some faces stays valid for them.
class Cleaner {
 public:
  Cleaner(Mesh* mesh, std::vector<uint8_t>* scaffold, double tolerance, double max_collapse)
      : mesh_(WithRoom(mesh, scaffold)),
        scaffold_(*scaffold),
        tolerance_(tolerance),
        max_collapse_(max_collapse),
        faces_of_(mesh->faces, mesh->vertices.size()),
        first_made_face_(mesh->faces.size()) {
    alive_.reserve(mesh_.faces.capacity());
    alive_.assign(mesh_.faces.size(), 1);
    touched_.reserve(mesh_.faces.capacity());
    box_.reserve(mesh_.faces.capacity());
    for (const Face& face : mesh_.faces) box_.push_back(AroundBox(FaceBox(face)));
    for (size_t v = 0; v < faces_of_.size(); ++v) {
      live_vertices_ += !faces_of_[static_cast<int32_t>(v)].empty();
    }
    std::vector<int32_t> all(mesh_.faces.size());
    std::iota(all.begin(), all.end(), 0);
    tree_.Build(box_, std::move(all));
  }

  const std::vector<uint8_t>& alive() const { return alive_; }
  bool Referenced(int32_t v) const { return !faces_of_[v].empty(); }
  bool MadeLastRound(int64_t f) const {
    return static_cast<size_t>(f) >= round_start_faces_ && alive_[f];
  }

  // The problem pairs with a face the last round made (faces) or a vertex of one (vertices), as
  // CheckFloatRobustness lists them with those faces in focus, found through the cleaner's own
  // trees: a query per made face or vertex instead of a box search over the whole mesh. The
  // queries reach twice the tolerance, and the tests are the check's own.
  ProblemPairs ProblemsOfMadeFaces(int64_t max_pairs) const {
    FaceTree made_now;  // many queries: a tree over this round's faces, not a scan
    made_now.Build(box_, recent_);
    const auto query = [&](const Box3& box, auto&& visit) {
      ForAliveFacesOverlapping(box, &made_now, visit);
    };
    ProblemPairs found;
    std::vector<int32_t> vertices;
    for (int32_t f : recent_) {
      if (!alive_[f]) continue;
      vertices.insert(vertices.end(), mesh_.faces[f].begin(), mesh_.faces[f].end());
      const Face& a = mesh_.faces[f];
      query(FaceBox(a).Grown(2 * tolerance_), [&](int32_t g) {
        if (g == f || SharedVertices(a, mesh_.faces[g]) > 0) return;
        const int64_t lo = std::min(f, g), hi = std::max(f, g);
        const Triangle p = Corners(mesh_.faces[lo]), q = Corners(mesh_.faces[hi]);
        if (FaceBox(mesh_.faces[lo]).Overlaps(FaceBox(mesh_.faces[hi])) &&
            TrianglesIntersectLikeOpen3d(p, q)) {
          found.crossing_faces.push_back({lo, hi});
        }
        if (TriangleDistance(p, q) <= tolerance_) found.close_faces.push_back({lo, hi});
      });
    }
    SortUnique(&vertices);
    for (int32_t v : vertices) {
      Box3 box;
      box.Add(mesh_.vertices[v]);
      query(box.Grown(2 * tolerance_), [&](int32_t g) {
        for (int32_t w : mesh_.faces[g]) {
          if (w != v && (mesh_.vertices[v] - mesh_.vertices[w]).norm() <= tolerance_) {
            found.near_vertices.push_back({std::min(v, w), std::max(v, w)});
          }
        }
      });
    }
    SortUnique(&found.near_vertices);
    SortUnique(&found.close_faces);
    SortUnique(&found.crossing_faces);
    const auto full = [&](size_t n) { return static_cast<int64_t>(n) >= max_pairs; };
    found.complete = !full(found.near_vertices.size()) && !full(found.close_faces.size()) &&
                     !full(found.crossing_faces.size());
    return found;
  }

  int64_t collapses() const { return collapses_; }
  int64_t splits() const { return splits_; }
  int64_t moves() const { return moves_; }

  // One pass over the listed problems; returns the operations done.
  int64_t Round(const ProblemPairs& problems) {
    std::vector<int32_t> made_before;
    for (size_t f = first_made_face_; f < mesh_.faces.size(); ++f) {
      if (alive_[f]) made_before.push_back(static_cast<int32_t>(f));
    }
    made_tree_.Build(box_, std::move(made_before));
    round_start_faces_ = mesh_.faces.size();
    recent_.clear();
    touched_.assign(mesh_.faces.size(), 0);
    const int64_t before = collapses_ + splits_ + moves_;
    for (const auto& pair : problems.near_vertices) {
      CollapseAround({pair[0], pair[1]});
    }
    std::set<std::pair<int64_t, int64_t>> face_pairs;
    for (const auto& p : problems.close_faces) face_pairs.insert({p[0], p[1]});
    for (const auto& p : problems.crossing_faces) face_pairs.insert({p[0], p[1]});
    for (const auto& [f, g] : face_pairs) {
      if (Touched(f) || Touched(g)) continue;  // changed this round: checked again next round
      const Face& a = mesh_.faces[f];
      const Face& b = mesh_.faces[g];
      if (TriangleDistance(Corners(a), Corners(b)) > tolerance_) {
        SplitLongestEdge(f, g);  // far apart: only Möller's relative snapping sees them touch
      } else if (!CollapseAround({a[0], a[1], a[2], b[0], b[1], b[2]}) &&
                 !MoveApart(static_cast<int32_t>(f), static_cast<int32_t>(g))) {
        // Two sheets too close, with no edge short enough to collapse (a thin wall whose two
        // sides are faces of 20 cm, half a millimetre apart), are moved apart above. In a
        // crumpled cluster of faces a tolerance or two across, every collapse and move of the
        // pair's own corners folds a face: collapse an edge of a neighbour instead, which
        // changes the pair's surroundings for the next round.
        std::vector<int32_t> ring;
        for (int32_t v : {a[0], a[1], a[2], b[0], b[1], b[2]}) {
          for (int32_t w : Neighbours(v)) ring.push_back(w);
        }
        CollapseAround(std::move(ring));
      }
    }
    return collapses_ + splits_ + moves_ - before;
  }

  // Drops dead faces and unreferenced vertices, renumbering `scaffold` along; the cleaner is
  // spent after it, so its search structures go first (at 10^6 vertices they and the compacted
  // copy on top were the cleanup's peak of memory).
  void Compact() {
    std::vector<FloatBox3>().swap(box_);
    tree_ = FaceTree();
    made_tree_ = FaceTree();
    faces_of_ = VertexFaceLists({}, 0);
    std::vector<Face> faces;
    faces.reserve(static_cast<size_t>(std::count(alive_.begin(), alive_.end(), 1)));
    for (size_t f = 0; f < mesh_.faces.size(); ++f) {
      if (alive_[f]) faces.push_back(mesh_.faces[f]);
    }
    std::vector<int32_t> index(mesh_.vertices.size(), -1);
    for (const Face& f : faces) {
      for (int32_t v : f) index[v] = 0;
    }
    const auto used = static_cast<size_t>(std::count(index.begin(), index.end(), 0));
    Mesh out;
    std::vector<uint8_t> scaffold;
    out.vertices.reserve(used);
    if (mesh_.HasColors()) out.vertex_colors.reserve(used);
    scaffold.reserve(used);
    out.faces.reserve(faces.size());
    for (size_t v = 0; v < index.size(); ++v) {
      if (index[v] < 0) continue;
      index[v] = static_cast<int32_t>(out.vertices.size());
      out.vertices.push_back(mesh_.vertices[v]);
      if (mesh_.HasColors()) out.vertex_colors.push_back(mesh_.vertex_colors[v]);
      scaffold.push_back(scaffold_[v]);
    }
    for (Face f : faces) {
      for (int32_t& v : f) v = index[v];
      out.faces.push_back(f);
    }
    mesh_ = std::move(out);
    scaffold_ = std::move(scaffold);
  }

 private:
  // Room for the faces and vertices the rounds make, reserved before the cleaner's structures
  // are built: a vector that outgrows its capacity mid-cleanup holds its old and new copies at
  // once, on top of everything else (at 10^6 vertices the cleanup is the coordinator's peak of
  // memory). Room never touched is not resident.
  static Mesh& WithRoom(Mesh* mesh, std::vector<uint8_t>* scaffold) {
    const auto room = [](size_t n) { return n + n / 4 + 1024; };
    mesh->faces.reserve(room(mesh->faces.size()));
    mesh->vertices.reserve(room(mesh->vertices.size()));
    if (mesh->HasColors()) mesh->vertex_colors.reserve(room(mesh->vertex_colors.size()));
    scaffold->reserve(room(scaffold->size()));
    return *mesh;
  }

  Triangle Corners(const Face& f) const {
    return {mesh_.vertices[f[0]], mesh_.vertices[f[1]], mesh_.vertices[f[2]]};
  }
  Box3 FaceBox(const Face& f) const {
    Box3 b;
    for (int32_t v : f) b.Add(mesh_.vertices[v]);
    return b;
  }
  bool Touched(int64_t f) const {
    return !alive_[f] || (static_cast<size_t>(f) < touched_.size() && touched_[f]);
  }

  std::vector<int32_t> Neighbours(int32_t v) const {
    std::vector<int32_t> out;
    for (int32_t f : faces_of_[v]) {
      for (int32_t w : mesh_.faces[f]) {
        if (w != v) out.push_back(w);
      }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  // Tries to remove one of `vertices` by collapsing one of its edges (shortest first), so that
  // every face around the problem is replaced by faces checked clean. True if one collapsed
  // (or the problem's faces changed already this round).
  bool CollapseAround(std::vector<int32_t> vertices) {
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    for (int32_t v : vertices) {
      if (faces_of_[v].empty()) return true;  // removed this round
      for (int32_t f : faces_of_[v]) {
        if (touched_[f]) return true;
      }
    }
    struct Candidate {
      double length;
      int32_t removed, kept;
    };
    std::vector<Candidate> candidates;
    for (int32_t u : vertices) {
      for (int32_t w : Neighbours(u)) {
        const double length = (mesh_.vertices[u] - mesh_.vertices[w]).norm();
        if (length > max_collapse_) continue;
        // A scaffold vertex never takes the place of a surface one.
        if (scaffold_[w] && !scaffold_[u]) continue;
        candidates.push_back({length, u, w});
      }
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return std::tie(a.length, a.removed, a.kept) < std::tie(b.length, b.removed, b.kept);
    });
    for (const Candidate& c : candidates) {
      if (TryCollapse(c.removed, c.kept)) return true;
    }
    return false;
  }

  // Faces f and g, closer than the tolerance and sharing no vertex: moves the corners of one of
  // them (or one corner) 2 tolerances away from the other, where that leaves fewer problems and
  // nothing forbidden: 4e-6 of the diagonal with the defaults (check-mesh's tolerance, times the
  // cleanup's margin, times 2). First along the line through their closest points (which
  // separates two sheets meeting at an angle), then along g's normal (two parallel sheets).
  // True if one moved.
  bool MoveApart(int32_t f, int32_t g) {
    const Face a = mesh_.faces[f], b = mesh_.faces[g];
    std::vector<std::pair<std::vector<int32_t>, Vector3d>> tries;
    const auto [on_a, on_b] = TriangleClosestPoints(Corners(a), Corners(b));
    const Vector3d gap = on_a - on_b;
    if (gap.norm() > 0) {
      const Vector3d away = 2 * tolerance_ * gap.normalized();  // moves a away from b
      const auto nearest = [&](const Face& face, const Vector3d& point) {
        int32_t best = face[0];
        for (int32_t v : face) {
          if ((mesh_.vertices[v] - point).norm() < (mesh_.vertices[best] - point).norm()) best = v;
        }
        return best;
      };
      tries.push_back({{a[0], a[1], a[2]}, away});
      tries.push_back({{b[0], b[1], b[2]}, -away});
      tries.push_back({{nearest(a, on_a)}, away});
      tries.push_back({{nearest(b, on_b)}, -away});
    }
    const Vector3d n = Normal(b);
    if (n.norm() > 0) {
      const Vector3d centre_a =
          (mesh_.vertices[a[0]] + mesh_.vertices[a[1]] + mesh_.vertices[a[2]]) / 3;
      const double side = n.dot(centre_a - mesh_.vertices[b[0]]) >= 0 ? 1.0 : -1.0;
      const Vector3d away = 2 * tolerance_ * side * n.normalized();
      tries.push_back({{a[0], a[1], a[2]}, away});
      tries.push_back({{b[0], b[1], b[2]}, -away});
      for (int32_t v : a) tries.push_back({{v}, away});
      for (int32_t v : b) tries.push_back({{v}, -away});
    }
    for (const auto& [vertices, delta] : tries) {
      if (TryMove(vertices, delta)) return true;
    }
    return false;
  }

  // Moves `vertices` by `delta`: each gets a moved copy and their faces are made anew on the
  // copies (the old vertices end unreferenced), if every face keeps its side and the change
  // improves (Improves).
  bool TryMove(const std::vector<int32_t>& vertices, const Vector3d& delta) {
    std::vector<int32_t> removed;
    for (int32_t v : vertices) {
      if (scaffold_[v] != scaffold_[vertices.front()]) return false;
      for (int32_t f : faces_of_[v]) {
        if (touched_[f]) return false;
        removed.push_back(f);
      }
    }
    std::sort(removed.begin(), removed.end());
    removed.erase(std::unique(removed.begin(), removed.end()), removed.end());
    const int32_t first = static_cast<int32_t>(mesh_.vertices.size());
    for (int32_t v : vertices) mesh_.vertices.push_back(mesh_.vertices[v] + delta);
    const auto moved = [&](int32_t w) {
      const auto it = std::find(vertices.begin(), vertices.end(), w);
      return it == vertices.end() ? w : first + static_cast<int32_t>(it - vertices.begin());
    };
    std::vector<Face> made;
    bool ok = true;
    for (int32_t f : removed) {
      Face face = mesh_.faces[f];
      const Vector3d old_normal = Normal(face);
      for (int32_t& w : face) w = moved(w);
      ok = ok && FlipFree(old_normal, face);
      made.push_back(face);
    }
    if (!ok || !Improves(removed, made, /*moved=*/true)) {
      mesh_.vertices.resize(first);
      return false;
    }
    for (int32_t v : vertices) {
      if (mesh_.HasColors()) mesh_.vertex_colors.push_back(mesh_.vertex_colors[v]);
      scaffold_.push_back(scaffold_[v]);
      faces_of_.AddVertex();
    }
    Apply(removed, made);
    ++moves_;
    return true;
  }

  bool TryCollapse(int32_t u, int32_t v) {
    // The link condition: u and v share exactly the two vertices opposite their edge.
    const std::vector<int32_t> nu = Neighbours(u), nv = Neighbours(v);
    std::vector<int32_t> common;
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    if (common.size() != 2) return false;
    if (live_vertices_ <= 4) return false;  // a tetrahedron cannot lose a vertex
    std::vector<int32_t> removed, kept_faces;
    std::vector<Face> made;
    for (int32_t f : faces_of_[u]) {
      Face face = mesh_.faces[f];
      removed.push_back(f);
      if (std::find(face.begin(), face.end(), v) != face.end()) continue;
      const Vector3d old_normal = Normal(face);
      for (int32_t& w : face) {
        if (w == u) w = v;
      }
      if (!FlipFree(old_normal, face)) return false;
      made.push_back(face);
    }
    if (!Improves(removed, made)) return false;
    Apply(removed, made);
    faces_of_.Clear(u);
    --live_vertices_;
    ++collapses_;
    return true;
  }

  void SplitLongestEdge(int64_t f, int64_t g) {
    int32_t a = -1, b = -1;
    double longest = 0;
    for (int64_t h : {f, g}) {
      const Face& face = mesh_.faces[h];
      for (int i = 0; i < 3; ++i) {
        const double length = (mesh_.vertices[face[i]] - mesh_.vertices[face[(i + 1) % 3]]).norm();
        if (length > longest) {
          longest = length;
          a = face[i];
          b = face[(i + 1) % 3];
        }
      }
    }
    if (a < 0 || longest < 4 * tolerance_) return;
    // The two faces of edge ab: (a, b, c) and (b, a, d) in their cyclic orders.
    std::vector<int32_t> removed;
    std::vector<Face> made;
    const int32_t m = static_cast<int32_t>(mesh_.vertices.size());
    for (int32_t h : faces_of_[a]) {
      const Face& face = mesh_.faces[h];
      for (int i = 0; i < 3; ++i) {
        const int32_t x = face[i], y = face[(i + 1) % 3], z = face[(i + 2) % 3];
        if (!((x == a && y == b) || (x == b && y == a))) continue;
        if (touched_[h]) return;
        removed.push_back(h);
        made.push_back({x, m, z});
        made.push_back({m, y, z});
      }
    }
    if (removed.size() != 2) return;
    mesh_.vertices.push_back((mesh_.vertices[a] + mesh_.vertices[b]) / 2);
    if (mesh_.HasColors()) mesh_.vertex_colors.push_back(mesh_.vertex_colors[a]);
    scaffold_.push_back(scaffold_[a] || scaffold_[b]);
    faces_of_.AddVertex();
    ++live_vertices_;
    Apply(removed, made);
    ++splits_;
  }

  Vector3d Normal(const Face& f) const {
    const Vector3d& p = mesh_.vertices[f[0]];
    return (mesh_.vertices[f[1]] - p).cross(mesh_.vertices[f[2]] - p);
  }

  // The face keeps its side (where its old normal is meaningful) and is no needle.
  bool FlipFree(const Vector3d& old_normal, const Face& face) const {
    const Vector3d n = Normal(face);
    double longest = 0;
    for (int i = 0; i < 3; ++i) {
      longest =
          std::max(longest, (mesh_.vertices[face[i]] - mesh_.vertices[face[(i + 1) % 3]]).norm());
    }
    if (n.norm() <= tolerance_ * longest) return false;  // height under the tolerance
    if (old_normal.norm() <= tolerance_ * longest) return true;
    return n.normalized().dot(old_normal.normalized()) > 0.2;
  }

  // An edge of x with no vertex of y crosses y (touching included).
  bool OppositeEdgeCrosses(const Face& x, const Face& y) const {
    const Triangle ty = Corners(y);
    for (int i = 0; i < 3; ++i) {
      const int32_t p = x[i], q = x[(i + 1) % 3];
      if (std::count(y.begin(), y.end(), p) > 0 || std::count(y.begin(), y.end(), q) > 0) continue;
      if (SegmentCrossesTriangle(mesh_.vertices[p], mesh_.vertices[q], ty)) return true;
    }
    return false;
  }

  enum class PairState { kClean, kFloatProblem, kForbidden };

  // Faces sharing no vertex: a float problem within the tolerance or when Open3D's test (either
  // order) calls them intersecting, forbidden so near that they may cross in exact arithmetic.
  // Faces sharing one vertex: forbidden when they cross (not coplanar, that is when an edge
  // opposite the shared vertex crosses the other face). Faces sharing an edge: forbidden when
  // folded onto each other.
  PairState Classify(const Face& a, const Face& b) const {
    const int shared = SharedVertices(a, b);
    if (shared == 0) {
      const Triangle ta = Corners(a), tb = Corners(b);
      const double distance = TriangleDistance(ta, tb);
      if (distance <= 0.01 * tolerance_) return PairState::kForbidden;
      if (distance <= tolerance_ || TrianglesIntersectLikeOpen3d(ta, tb) ||
          TrianglesIntersectLikeOpen3d(tb, ta)) {
        return PairState::kFloatProblem;
      }
      return PairState::kClean;
    }
    if (shared == 1) {
      return OppositeEdgeCrosses(a, b) || OppositeEdgeCrosses(b, a) ? PairState::kForbidden
                                                                    : PairState::kClean;
    }
    const Vector3d na = Normal(a), nb = Normal(b);
    const bool folded =
        na.norm() > 0 && nb.norm() > 0 && na.normalized().dot(nb.normalized()) < -0.999;
    return folded ? PairState::kForbidden : PairState::kClean;
  }

  // Cosine between the normals of two faces sharing an edge (1 when one is degenerate).
  double FoldCosine(const Face& a, const Face& b) const {
    const Vector3d na = Normal(a), nb = Normal(b);
    if (!(na.norm() > 0) || !(nb.norm() > 0)) return 1;
    return na.normalized().dot(nb.normalized());
  }

  // The problem pairs between `faces` and the alive faces near them (those in `skip` excepted)
  // and among `faces`; -1 when `forbid` and a pair is forbidden (else such a pair counts as a
  // problem). `before`, when given, holds what each of `faces` replaces (a move: the same
  // vertices, some moved): a fold that was there before is allowed as long as it does not get
  // sharper, so that a sheet next to a fin can still be moved.
  int64_t CountProblems(const std::vector<Face>& faces, const std::vector<int32_t>& skip,
                        bool forbid, const std::vector<Face>* before = nullptr) const {
    int64_t problems = 0;
    bool forbidden = false;
    auto add = [&](const Face& x, const Face& y, const Face* old_x, const Face* old_y) {
      PairState state = Classify(x, y);
      if (state == PairState::kForbidden && old_x != nullptr && SharedVertices(x, y) == 2 &&
          Classify(*old_x, *old_y) == PairState::kForbidden &&
          FoldCosine(x, y) >= FoldCosine(*old_x, *old_y)) {
        state = PairState::kClean;  // a fold that was there, no sharper
      }
      if (state == PairState::kForbidden && forbid) forbidden = true;
      problems += state != PairState::kClean;
    };
    for (size_t i = 0; i < faces.size() && !forbidden; ++i) {
      const Face* old_i = before != nullptr ? &(*before)[i] : nullptr;
      const Box3 box = FaceBox(faces[i]).Grown(tolerance_);
      ForAliveFacesOverlapping(box, nullptr, [&](int32_t f) {
        if (forbidden || std::find(skip.begin(), skip.end(), f) != skip.end()) return;
        add(faces[i], mesh_.faces[f], old_i, &mesh_.faces[f]);
      });
      for (size_t j = 0; j < i && !forbidden; ++j) {
        add(faces[i], faces[j], old_i, before != nullptr ? &(*before)[j] : nullptr);
      }
    }
    return forbidden ? -1 : problems;
  }

  // Calls visit(f) for every alive face whose box overlaps `box`: the trees' float boxes find a
  // superset, each face's exact double box decides. This round's faces come from `made_now`
  // when given, else from a scan of them.
  template <typename Visit>
  void ForAliveFacesOverlapping(const Box3& box, const FaceTree* made_now, Visit&& visit) const {
    const auto exact = [&](int32_t f) {
      if (alive_[f] && FaceBox(mesh_.faces[f]).Overlaps(box)) visit(f);
    };
    const FloatBox3 search = AroundBox(box);
    tree_.Query(search, exact);
    made_tree_.Query(search, exact);
    if (made_now != nullptr) {
      made_now->Query(search, exact);
    } else {
      for (int32_t f : recent_) exact(f);
    }
  }

  static int SharedVertices(const Face& a, const Face& b) {
    int shared = 0;
    for (int32_t x : a) shared += std::count(b.begin(), b.end(), x) > 0;
    return shared;
  }

  // Replacing `removed` by `made` is worth it: nothing forbidden, and fewer problem pairs.
  // `moved`: made[k] is removed[k] with some vertices moved (TryMove), so folds already there
  // may stay.
  bool Improves(const std::vector<int32_t>& removed, const std::vector<Face>& made,
                bool moved = false) const {
    std::vector<Face> old;
    for (int32_t f : removed) old.push_back(mesh_.faces[f]);
    const int64_t after = CountProblems(made, removed, true, moved ? &old : nullptr);
    if (after < 0) return false;
    if (after == 0) return true;
    return after < CountProblems(old, removed, false);
  }

  void Apply(const std::vector<int32_t>& removed, const std::vector<Face>& made) {
    for (int32_t f : removed) {
      alive_[f] = 0;
      touched_[f] = 1;
      for (int32_t v : mesh_.faces[f]) faces_of_.Remove(v, f);
    }
    for (const Face& face : made) {
      const int32_t f = static_cast<int32_t>(mesh_.faces.size());
      mesh_.faces.push_back(face);
      alive_.push_back(1);
      touched_.push_back(1);
      box_.push_back(AroundBox(FaceBox(face)));
      recent_.push_back(f);
      for (int32_t v : face) faces_of_.Add(v, f);
    }
  }

  Mesh& mesh_;
  std::vector<uint8_t>& scaffold_;
  const double tolerance_, max_collapse_;
  VertexFaceLists faces_of_;      // per vertex: its alive faces
  std::vector<uint8_t> alive_;    // per face
  std::vector<FloatBox3> box_;    // per face
  std::vector<uint8_t> touched_;  // per face: removed or made this round
  std::vector<int32_t> recent_;   // faces made this round (in neither tree)
  const size_t first_made_face_;  // faces from this index on were made
  size_t round_start_faces_ = 0;  // ... from this one on, this round
  FaceTree tree_;                 // the faces the cleanup started with
  FaceTree made_tree_;            // made in earlier rounds, alive at this one's start
  int64_t live_vertices_ = 0;     // vertices with a face
  int64_t collapses_ = 0, splits_ = 0, moves_ = 0;
};

ProblemPairs ListedProblems(const FloatRobustnessReport& r) {
  ProblemPairs p;
  p.near_vertices = r.near_vertex_examples;
  p.close_faces = r.close_face_pair_examples;
  p.crossing_faces = r.float_intersection_examples;
  p.complete = !r.near_vertex_pairs_truncated && !r.close_face_pairs_truncated &&
               !r.float_intersections_truncated &&
               static_cast<int64_t>(p.near_vertices.size()) == r.num_near_vertex_pairs &&
               static_cast<int64_t>(p.close_faces.size()) == r.num_close_face_pairs &&
               static_cast<int64_t>(p.crossing_faces.size()) == r.num_float_intersections;
  return p;
}

ProblemPairs CheckWholeMesh(const Mesh& mesh, const std::vector<uint8_t>& alive,
                            const FloatRobustnessOptions& check) {
  return ListedProblems(CheckFloatRobustness(mesh, alive, check));
}

// The problems of the mesh after a round, as a whole-mesh check would list them, from the
// problems of the faces the round made: vertices never move (a move makes new ones), so a pair
// of faces the round left alive, or of vertices still used, is a problem exactly when it was one
// before. Falls back to the whole check where a list was cut short.
ProblemPairs CheckAfterRound(const Mesh& mesh, const Cleaner& cleaner, const ProblemPairs& before,
                             const FloatRobustnessOptions& check) {
  if (!before.complete) return CheckWholeMesh(mesh, cleaner.alive(), check);
  ProblemPairs after = cleaner.ProblemsOfMadeFaces(check.max_pairs);
  if (!after.complete) return CheckWholeMesh(mesh, cleaner.alive(), check);
  // Vertices never move: a near pair whose vertices are both still used is still one.
  for (const auto& pair : before.near_vertices) {
    if (cleaner.Referenced(pair[0]) && cleaner.Referenced(pair[1])) {
      after.near_vertices.push_back(pair);
    }
  }
  // Faces listed before are older than the round: alive, the round left them alone.
  const auto carry = [&](const std::vector<std::array<int64_t, 2>>& pairs,
                         std::vector<std::array<int64_t, 2>>* out) {
    for (const auto& pair : pairs) {
      if (cleaner.alive()[pair[0]] && cleaner.alive()[pair[1]]) out->push_back(pair);
    }
  };
  carry(before.close_faces, &after.close_faces);
  carry(before.crossing_faces, &after.crossing_faces);
  SortUnique(&after.near_vertices);
  SortUnique(&after.close_faces);
  SortUnique(&after.crossing_faces);
  // The whole check stops each list at max_pairs; past that it lists other pairs.
  const auto full = [&](size_t n) { return static_cast<int64_t>(n) >= check.max_pairs; };
  if (full(after.near_vertices.size()) || full(after.close_faces.size()) ||
      full(after.crossing_faces.size())) {
    return CheckWholeMesh(mesh, cleaner.alive(), check);
  }
  return after;
}

}  // namespace

FloatCleanupStats CleanForFloatingPoint(Mesh* mesh, std::vector<uint8_t>* scaffold,
                                        const FloatCleanupOptions& options,
                                        const std::function<Mesh()>& original) {
  Timer timer;
  options.check.Check();
  std::vector<uint8_t> no_scaffold;
  if (scaffold == nullptr) {
    no_scaffold.assign(mesh->vertices.size(), 0);
    scaffold = &no_scaffold;
  }
  MS_CHECK(scaffold->size() == mesh->vertices.size()) << "one scaffold flag per vertex";
  FloatCleanupStats stats;
  const std::vector<uint8_t> usable(mesh->faces.size(), 1);
  // The cleanup works at `margin` times the checker's tolerance, so that what it leaves passes
  // the check with room to spare; one full check, at that tolerance.
  stats.tolerance = options.margin * FloatCheckTolerance(*mesh, usable, options.check);
  FloatRobustnessOptions check = options.check;
  check.absolute_tolerance = stats.tolerance;
  // The cleanup must see every problem: with the lists cut at check-mesh's max_pairs, a round
  // fixes only the listed ones and every later round checks the whole mesh again. Four pairs a
  // face is more than any mesh worth cleaning has (the whole-check fallback stays past it).
  check.max_pairs =
      std::max<int64_t>(check.max_pairs, 4 * static_cast<int64_t>(mesh->faces.size()));
  check.max_examples = static_cast<int>(std::min<int64_t>(check.max_pairs, 1 << 30));
  const FloatRobustnessReport report = CheckFloatRobustness(*mesh, usable, check);
  ProblemPairs problems = ListedProblems(report);
  stats.problems_before = problems.Count();  // every pair found is listed
  const double max_collapse = options.max_collapse_fraction * report.diagonal;
  // Splits help only in numbers, and clusters of near vertices can defeat the collapses: a
  // cleanup that ends with no fewer problems leaves the mesh as it was.
  int64_t problems_left = stats.problems_before;
  // Only a cleanup that ran can need undoing.
  Mesh own_copy;
  std::vector<uint8_t> original_scaffold;
  if (problems_left > 0) {
    if (!original) own_copy = *mesh;
    original_scaffold = *scaffold;
    // The whole check's boxes are gone: the cleaner starts from what the heap holds (at 10^6
    // vertices the cleanup is the coordinator's peak of memory).
    ReleaseFreeMemory();
    Cleaner cleaner(mesh, scaffold, stats.tolerance, max_collapse);
    while (problems_left > 0 && stats.rounds < options.max_rounds) {
      ++stats.rounds;
      if (cleaner.Round(problems) == 0) break;
      problems = CheckAfterRound(*mesh, cleaner, problems, check);
      if (options.verify_rechecks) {
        const ProblemPairs whole = CheckWholeMesh(*mesh, cleaner.alive(), check);
        MS_CHECK(problems.near_vertices == whole.near_vertices &&
                 problems.close_faces == whole.close_faces &&
                 problems.crossing_faces == whole.crossing_faces)
            << "float cleanup, round " << stats.rounds
            << ": the re-check of what the round made differs from a whole-mesh check";
      }
      problems_left = problems.Count();
    }
    cleaner.Compact();
    stats.collapses = cleaner.collapses();
    stats.splits = cleaner.splits();
    stats.moves = cleaner.moves();
  }
  stats.problems_after = problems_left;
  if (stats.problems_after > 0 && stats.problems_after >= stats.problems_before) {
    if (original) {
      *mesh = original();
      MS_CHECK(mesh->vertices.size() == original_scaffold.size())
          << "float cleanup: `original` made another mesh";
    } else {
      *mesh = std::move(own_copy);
    }
    *scaffold = original_scaffold;
    stats.problems_after = stats.problems_before;
    stats.collapses = stats.splits = stats.moves = 0;
  }
  stats.seconds = timer.Seconds();
  return stats;
}

}  // namespace ms
