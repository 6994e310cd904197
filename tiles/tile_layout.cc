#include "tiles/tile_layout.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "base/error.h"

namespace ms {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

int LongestAxis(const std::vector<Eigen::Vector3d>& points, size_t begin, size_t end) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = -lo;
  for (size_t i = begin; i < end; ++i) {
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  if (begin == end) return 0;
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  return axis;
}

}  // namespace

TileLayout TileLayout::Split(const std::vector<Eigen::Vector3d>& points, int tiles) {
  if (tiles < 1)
    throw InputError("tiles: the tile count must be at least 1, not " + std::to_string(tiles));
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw InputError("tiles: point " + std::to_string(i) + " is not finite");
    }
  }
  TileLayout layout;
  layout.num_tiles_ = tiles;
  std::vector<Eigen::Vector3d> work = points;
  layout.Build(work, 0, work.size(), tiles, Eigen::Vector3d::Constant(-kInf),
               Eigen::Vector3d::Constant(kInf));
  layout.ComputeRegions();
  return layout;
}

// Splits points[begin, end) among `tiles` tiles; returns the node's index. Tiles are numbered
// in the order their leaves are made (low side first), so the numbering follows the tree.
int TileLayout::Build(std::vector<Eigen::Vector3d>& points, size_t begin, size_t end, int tiles,
                      const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  if (tiles == 1) {
    nodes_[index].tile = leaves_made_++;
    return index;
  }
  const int low_tiles = tiles / 2;
  const int axis = LongestAxis(points, begin, end);
  double split = 0;
  size_t middle = begin;
  if (begin < end) {
    // The first point of the high side in sorted order: ranks before it go low.
    const size_t rank = begin + (end - begin) * low_tiles / tiles;
    auto by_axis = [axis](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return a[axis] < b[axis];
    };
    std::nth_element(points.begin() + begin, points.begin() + rank, points.begin() + end, by_axis);
    split = points[rank][axis];
    middle = static_cast<size_t>(
        std::partition(points.begin() + begin, points.begin() + end,
                       [&](const Eigen::Vector3d& p) { return p[axis] < split; }) -
        points.begin());
  } else {
    // No points to balance: halve the region where it is bounded.
    split = std::isfinite(lo[axis]) && std::isfinite(hi[axis]) ? 0.5 * (lo[axis] + hi[axis])
            : std::isfinite(lo[axis])                          ? lo[axis]
            : std::isfinite(hi[axis])                          ? hi[axis]
                                                               : 0.0;
  }
  nodes_[index].axis = axis;
  nodes_[index].split = split;
  Eigen::Vector3d low_hi = hi, high_lo = lo;
  low_hi[axis] = split;
  high_lo[axis] = split;
  const int low = Build(points, begin, middle, low_tiles, lo, low_hi);
  const int high = Build(points, middle, end, tiles - low_tiles, high_lo, hi);
  nodes_[index].low = low;
  nodes_[index].high = high;
  return index;
}

void TileLayout::ComputeRegions() {
  lower_.assign(num_tiles_, Eigen::Vector3d::Constant(-kInf));
  upper_.assign(num_tiles_, Eigen::Vector3d::Constant(kInf));
  // Depth-first with each node's region.
  struct Item {
    int node;
    Eigen::Vector3d lo, hi;
  };
  std::vector<Item> stack = {
      {0, Eigen::Vector3d::Constant(-kInf), Eigen::Vector3d::Constant(kInf)}};
  while (!stack.empty()) {
    Item item = stack.back();
    stack.pop_back();
    const Node& n = nodes_[item.node];
    if (n.tile >= 0) {
      lower_[n.tile] = item.lo;
      upper_[n.tile] = item.hi;
      continue;
    }
    Item low = item, high = item;
    low.node = n.low;
    low.hi[n.axis] = n.split;
    high.node = n.high;
    high.lo[n.axis] = n.split;
    stack.push_back(low);
    stack.push_back(high);
  }
}

int TileLayout::TileOf(const Eigen::Vector3d& p) const {
  int node = 0;
  while (nodes_[node].tile < 0) {
    const Node& n = nodes_[node];
    node = p[n.axis] < n.split ? n.low : n.high;
  }
  return nodes_[node].tile;
}

std::vector<int> TileLayout::TilesMeeting(const Eigen::Vector3d& lo,
                                          const Eigen::Vector3d& hi) const {
  std::vector<int> tiles;
  CollectMeeting(0, lo, hi, &tiles);
  std::sort(tiles.begin(), tiles.end());
  return tiles;
}

void TileLayout::CollectMeeting(int node, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                std::vector<int>* tiles) const {
  const Node& n = nodes_[node];
  if (n.tile >= 0) {
    tiles->push_back(n.tile);
    return;
  }
  // The low side is [.., split): it meets [lo, hi] if lo < split.
  if (lo[n.axis] < n.split) CollectMeeting(n.low, lo, hi, tiles);
  if (hi[n.axis] >= n.split) CollectMeeting(n.high, lo, hi, tiles);
}

std::string TileLayout::ToJson() const {
  nlohmann::json nodes = nlohmann::json::array();
  for (const Node& n : nodes_) {
    if (n.tile >= 0) {
      nodes.push_back({{"tile", n.tile}});
    } else {
      nodes.push_back({{"axis", n.axis}, {"split", n.split}, {"low", n.low}, {"high", n.high}});
    }
  }
  // JSON has no infinity: an unbounded side is null.
  auto bound = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  nlohmann::json regions = nlohmann::json::array();
  for (int t = 0; t < num_tiles_; ++t) {
    nlohmann::json lo = nlohmann::json::array(), hi = nlohmann::json::array();
    for (int a = 0; a < 3; ++a) {
      lo.push_back(bound(lower_[t][a]));
      hi.push_back(bound(upper_[t][a]));
    }
    regions.push_back({{"tile", t}, {"lower", lo}, {"upper", hi}});
  }
  nlohmann::json j = {{"tiles", num_tiles_}, {"nodes", nodes}, {"regions", regions}};
  return j.dump(1) + "\n";
}

TileLayout TileLayout::FromJson(const std::string& text, const std::string& source) {
  auto bad = [&](const std::string& what) {
    return InputError(source + ": " + what + " (a tile layout as `reconstruct --tiles` writes)");
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw bad(std::string("not JSON: ") + e.what());
  }
  TileLayout layout;
  try {
    layout.num_tiles_ = j.at("tiles").get<int>();
    for (const auto& n : j.at("nodes")) {
      Node node;
      if (n.contains("tile")) {
        node.tile = n.at("tile").get<int>();
      } else {
        node.axis = n.at("axis").get<int>();
        node.split = n.at("split").get<double>();
        node.low = n.at("low").get<int>();
        node.high = n.at("high").get<int>();
      }
      layout.nodes_.push_back(node);
    }
  } catch (const nlohmann::json::exception& e) {
    throw bad(std::string("field missing or of the wrong type: ") + e.what());
  }
  // The tree must be one the walks terminate in: children after their parent, each tile once.
  const int count = static_cast<int>(layout.nodes_.size());
  if (layout.num_tiles_ < 1 || count != 2 * layout.num_tiles_ - 1) {
    throw bad("'nodes' must hold 2 * tiles - 1 nodes");
  }
  std::vector<int> tile_seen(layout.num_tiles_, 0), parents(count, 0);
  for (int i = 0; i < count; ++i) {
    const Node& n = layout.nodes_[i];
    const std::string where = "node " + std::to_string(i);
    if (n.tile >= 0) {
      if (n.tile >= layout.num_tiles_ || tile_seen[n.tile]++) {
        throw bad(where + ": tile out of range or repeated");
      }
      continue;
    }
    if (n.axis < 0 || n.axis > 2 || !std::isfinite(n.split) || n.low <= i || n.high <= i ||
        n.low >= count || n.high >= count || n.low == n.high) {
      throw bad(where + ": bad axis, split or child");
    }
    if (parents[n.low]++ || parents[n.high]++) throw bad(where + ": a child with two parents");
  }
  layout.ComputeRegions();
  return layout;
}

}  // namespace ms
