// A minimum s-t cut of a graph with integer capacities (Boykov-Kolmogorov max-flow, from
// Boost.Graph): which nodes stay on the source's side. The free-space cut of the Delaunay cells
// (--manifold.visibility cut, docs/design/manifold.md) is its one user. Internal to manifold/.
#pragma once

#include <cstdint>
#include <vector>

namespace ms::manifold_detail {

// A pair of opposite arcs between nodes a and b: cutting a (source side) from b (sink side)
// costs a_to_b, the other way b_to_a.
struct CutEdge {
  int32_t a = 0, b = 0;
  int64_t a_to_b = 0, b_to_a = 0;
};

// Nodes 0..n-1, each with a capacity from the source and one to the sink (both >= 0), and the
// edges between them. Returns one flag per node: 1 where the node is on the source's side of a
// minimum cut (the side reachable from the source in the residual graph), 0 otherwise. The same
// graph gives the same flags.
std::vector<uint8_t> SourceSideOfMinCut(const std::vector<int64_t>& from_source,
                                        const std::vector<int64_t>& to_sink,
                                        const std::vector<CutEdge>& edges);

}  // namespace ms::manifold_detail
