// The spatial split of a scene into tiles, each the charge of its own coordinator
// (docs/design/scalability.md, "Tiles"): a k-d tree whose leaves are the tiles, each split at
// the point that balances the points between its two sides along the longest extent.
//
//   TileLayout layout = TileLayout::Split(points, 8);
//   int tile = layout.TileOf(p);      // every point of space lies in exactly one tile
//   WriteFile(run / "tiles.json", layout.ToJson());
//
// Pass the scene's points, not the Steiner points the manifold adds: those fill a box enlarged
// around the scene, whose long sides across a street would put seams along it.
//
// The leaves cover all of space: the outer sides of the outer tiles are unbounded, so a point
// found later (a swept point) always has a tile. A split is half-open: coordinate < split goes
// to the low side. The layout depends only on the points and the tile count.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace ms {

class TileLayout {
 public:
  // Splits `points` into `tiles` (>= 1) tiles holding as near equal shares as the ties along a
  // split axis allow; a node of n tiles gives floor(n / 2) of them to its low side. Throws
  // InputError for a tile count below 1 or a non-finite point.
  static TileLayout Split(const std::vector<Eigen::Vector3d>& points, int tiles);
  // The layout ToJson wrote; `source` names the file in errors. Throws InputError for a
  // malformed layout.
  static TileLayout FromJson(const std::string& json, const std::string& source);

  int num_tiles() const { return num_tiles_; }
  // The tile whose region holds p.
  int TileOf(const Eigen::Vector3d& p) const;
  // A tile's region as [lo, hi) per axis; outer sides are +-infinity.
  Eigen::Vector3d lower(int tile) const { return lower_[tile]; }
  Eigen::Vector3d upper(int tile) const { return upper_[tile]; }
  // The tiles whose regions meet the closed box [lo, hi].
  std::vector<int> TilesMeeting(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;

  // The layout as JSON: the split tree and every tile's region, for the run folder.
  std::string ToJson() const;

 private:
  // A split node (tile < 0) or a leaf.
  struct Node {
    int tile = -1;
    int axis = 0;
    double split = 0;
    int low = -1, high = -1;  // child node indices
  };
  int Build(std::vector<Eigen::Vector3d>& points, size_t begin, size_t end, int tiles,
            const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
  void CollectMeeting(int node, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                      std::vector<int>* tiles) const;
  void ComputeRegions();

  int num_tiles_ = 0;
  int leaves_made_ = 0;      // while Split builds the tree
  std::vector<Node> nodes_;  // nodes_[0] is the root
  std::vector<Eigen::Vector3d> lower_, upper_;
};

}  // namespace ms
