#include "manifold/steiner_sight.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/check.h"

namespace ms {
namespace {

// One camera's view cut into bins: the nearest depth around each bin (itself and its 8
// neighbours; infinity where none of them holds a point) and the farthest depth in it.
class DepthBins {
 public:
  explicit DepthBins(const ManifoldCamera& camera)
      : camera_(camera),
        nearest_(kSightBins * kSightBins, kInfinity),
        farthest_(kSightBins * kSightBins, -kInfinity) {}

  void Add(const Eigen::Vector3d& world) {
    double depth;
    const int bin = BinOf(world, &depth);
    if (bin < 0) return;
    nearest_[bin] = std::min(nearest_[bin], static_cast<float>(depth));
    farthest_[bin] = std::max(farthest_[bin], static_cast<float>(depth));
  }

  // After the last Add: the nearest depths over each bin's 3 x 3 neighbourhood.
  void Finish() {
    std::vector<float> around(nearest_.size(), kInfinity);
    for (int y = 0; y < kSightBins; ++y) {
      for (int x = 0; x < kSightBins; ++x) {
        float nearest = kInfinity;
        for (int ny = std::max(0, y - 1); ny <= std::min(kSightBins - 1, y + 1); ++ny) {
          for (int nx = std::max(0, x - 1); nx <= std::min(kSightBins - 1, x + 1); ++nx) {
            nearest = std::min(nearest, nearest_[ny * kSightBins + nx]);
          }
        }
        around[y * kSightBins + x] = nearest;
      }
    }
    nearest_ = std::move(around);
  }

  enum class Side { kOutOfView, kNoPoints, kFront, kBetween, kBehind };

  Side SideOf(const Eigen::Vector3d& world) const {
    double depth;
    const int bin = BinOf(world, &depth);
    if (bin < 0) return Side::kOutOfView;
    if (!std::isfinite(nearest_[bin])) return Side::kNoPoints;
    if (depth < nearest_[bin]) return Side::kFront;
    return depth > farthest_[bin] ? Side::kBehind : Side::kBetween;
  }

 private:
  static constexpr float kInfinity = std::numeric_limits<float>::infinity();

  // The bin `world` projects into (-1 if outside the view or behind the camera).
  int BinOf(const Eigen::Vector3d& world, double* depth) const {
    const Eigen::Vector3d x = camera_.R * (world - camera_.center);
    if (!(x.z() > 0)) return -1;
    const double u = (x.x() / x.z() - camera_.u_min) / (camera_.u_max - camera_.u_min);
    const double v = (x.y() / x.z() - camera_.v_min) / (camera_.v_max - camera_.v_min);
    if (!(u >= 0 && u < 1 && v >= 0 && v < 1)) return -1;
    *depth = x.z();
    return static_cast<int>(v * kSightBins) * kSightBins + static_cast<int>(u * kSightBins);
  }

  const ManifoldCamera& camera_;
  std::vector<float> nearest_, farthest_;
};

}  // namespace

std::vector<uint8_t> HiddenInEveryView(const std::vector<Eigen::Vector3d>& candidates,
                                       const std::vector<RayPoint>& points,
                                       const std::vector<ManifoldCamera>& cameras) {
  std::vector<std::vector<int32_t>> observed(cameras.size());
  for (size_t i = 0; i < points.size(); ++i) {
    for (const int32_t c : points[i].cameras) {
      MS_CHECK(c >= 0 && static_cast<size_t>(c) < cameras.size()) << "camera index out of range";
      observed[c].push_back(static_cast<int32_t>(i));
    }
  }
  std::vector<uint8_t> behind_somewhere(candidates.size(), 0), refused(candidates.size(), 0);
  for (size_t c = 0; c < cameras.size(); ++c) {
    if (observed[c].empty()) continue;
    DepthBins bins(cameras[c]);
    for (const int32_t i : observed[c]) bins.Add(points[i].position);
    bins.Finish();
    for (size_t k = 0; k < candidates.size(); ++k) {
      switch (bins.SideOf(candidates[k])) {
        case DepthBins::Side::kBehind:
          behind_somewhere[k] = 1;
          break;
        case DepthBins::Side::kFront:
        case DepthBins::Side::kNoPoints:
          refused[k] = 1;
          break;
        default:
          break;
      }
    }
  }
  std::vector<uint8_t> hidden(candidates.size());
  for (size_t k = 0; k < candidates.size(); ++k) hidden[k] = behind_somewhere[k] && !refused[k];
  return hidden;
}

}  // namespace ms
