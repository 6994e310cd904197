#include "manifold/steiner_sight.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/check.h"

namespace ms {
namespace {

// One camera's view cut into bins: how many of the points it observes fall in each, the nearest
// depth there and around (the bin and its 8 neighbours; infinity where none holds a point) and
// the farthest depth in the bin.
class DepthBins {
 public:
  explicit DepthBins(const ManifoldCamera& camera)
      : camera_(camera),
        count_(kSightBins * kSightBins, 0),
        nearest_(kSightBins * kSightBins, kInfinity),
        nearest_around_(kSightBins * kSightBins, kInfinity),
        farthest_(kSightBins * kSightBins, -kInfinity) {}

  void Add(const Eigen::Vector3d& world) {
    double depth;
    const int bin = BinOf(world, &depth);
    if (bin < 0) return;
    ++count_[bin];
    nearest_[bin] = std::min(nearest_[bin], static_cast<float>(depth));
    farthest_[bin] = std::max(farthest_[bin], static_cast<float>(depth));
  }

  // After the last Add.
  void Finish() {
    for (int y = 0; y < kSightBins; ++y) {
      for (int x = 0; x < kSightBins; ++x) {
        float nearest = kInfinity;
        for (int ny = std::max(0, y - 1); ny <= std::min(kSightBins - 1, y + 1); ++ny) {
          for (int nx = std::max(0, x - 1); nx <= std::min(kSightBins - 1, x + 1); ++nx) {
            nearest = std::min(nearest, nearest_[ny * kSightBins + nx]);
          }
        }
        nearest_around_[y * kSightBins + x] = nearest;
      }
    }
  }

  enum class Side { kOutOfView, kNoPoints, kFront, kBetween, kBehind };

  struct Seen {
    Side side = Side::kOutOfView;
    // Where kFront and the bin itself holds points: this camera's rays expected through a disc
    // of radius r facing it, from its points' density over the bin.
    double rays_through_disc = 0;
  };

  Seen See(const Eigen::Vector3d& world, double r) const {
    double depth;
    const int bin = BinOf(world, &depth);
    Seen seen;
    if (bin < 0) return seen;
    if (!std::isfinite(nearest_around_[bin])) {
      seen.side = Side::kNoPoints;
    } else if (depth < nearest_around_[bin]) {
      seen.side = Side::kFront;
      const double bin_area = (camera_.u_max - camera_.u_min) * (camera_.v_max - camera_.v_min) *
                              depth * depth / (kSightBins * kSightBins);
      seen.rays_through_disc = count_[bin] * M_PI * r * r / bin_area;
    } else {
      seen.side = depth > farthest_[bin] ? Side::kBehind : Side::kBetween;
    }
    return seen;
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
  std::vector<int32_t> count_;
  std::vector<float> nearest_, nearest_around_, farthest_;
};

}  // namespace

std::vector<SteinerSight> ClassifyBySight(const std::vector<Eigen::Vector3d>& candidates,
                                          const std::vector<double>& clearance,
                                          const std::vector<RayPoint>& points,
                                          const std::vector<ManifoldCamera>& cameras,
                                          double median_spacing) {
  MS_CHECK(clearance.size() == candidates.size()) << "one clearance per candidate";
  std::vector<std::vector<int32_t>> observed(cameras.size());
  for (size_t i = 0; i < points.size(); ++i) {
    for (const int32_t c : points[i].cameras) {
      MS_CHECK(c >= 0 && static_cast<size_t>(c) < cameras.size()) << "camera index out of range";
      observed[c].push_back(static_cast<int32_t>(i));
    }
  }
  std::vector<uint8_t> behind_somewhere(candidates.size(), 0), refused(candidates.size(), 0);
  std::vector<double> rays(candidates.size(), 0);
  for (size_t c = 0; c < cameras.size(); ++c) {
    if (observed[c].empty()) continue;
    DepthBins bins(cameras[c]);
    for (const int32_t i : observed[c]) bins.Add(points[i].position);
    bins.Finish();
    for (size_t k = 0; k < candidates.size(); ++k) {
      const DepthBins::Seen seen = bins.See(candidates[k], 0.5 * clearance[k]);
      switch (seen.side) {
        case DepthBins::Side::kBehind:
          behind_somewhere[k] = 1;
          break;
        case DepthBins::Side::kFront:
          refused[k] = 1;
          rays[k] += seen.rays_through_disc;
          break;
        case DepthBins::Side::kNoPoints:
          refused[k] = 1;
          break;
        default:
          break;
      }
    }
  }
  std::vector<SteinerSight> sight(candidates.size(), SteinerSight::kDrop);
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (behind_somewhere[k] && !refused[k]) {
      sight[k] = SteinerSight::kHidden;
    } else if (rays[k] >= kOpenAirRays && clearance[k] >= kOpenAirSpacings * median_spacing) {
      sight[k] = SteinerSight::kOpenAir;
    }
  }
  return sight;
}

}  // namespace ms
