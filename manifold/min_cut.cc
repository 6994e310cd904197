#include "manifold/min_cut.h"

// GCC sees Boost.Graph's optional edge iterators as maybe uninitialized (a false alarm).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>
#pragma GCC diagnostic pop

#include "base/check.h"

namespace ms::manifold_detail {
namespace {

using Traits = boost::adjacency_list_traits<boost::vecS, boost::vecS, boost::directedS>;
using Graph = boost::adjacency_list<
    boost::vecS, boost::vecS, boost::directedS,
    boost::property<
        boost::vertex_color_t, boost::default_color_type,
        boost::property<boost::vertex_distance_t, int64_t,
                        boost::property<boost::vertex_predecessor_t, Traits::edge_descriptor>>>,
    boost::property<
        boost::edge_capacity_t, int64_t,
        boost::property<boost::edge_residual_capacity_t, int64_t,
                        boost::property<boost::edge_reverse_t, Traits::edge_descriptor>>>>;

// An arc u -> v of capacity c and its reverse of capacity c_back.
void AddArcPair(Graph& g, size_t u, size_t v, int64_t c, int64_t c_back) {
  const auto forward = boost::add_edge(u, v, g).first;
  const auto backward = boost::add_edge(v, u, g).first;
  boost::put(boost::edge_capacity, g, forward, c);
  boost::put(boost::edge_capacity, g, backward, c_back);
  boost::put(boost::edge_reverse, g, forward, backward);
  boost::put(boost::edge_reverse, g, backward, forward);
}

}  // namespace

std::vector<uint8_t> SourceSideOfMinCut(const std::vector<int64_t>& from_source,
                                        const std::vector<int64_t>& to_sink,
                                        const std::vector<CutEdge>& edges) {
  MS_CHECK(from_source.size() == to_sink.size());
  const size_t n = from_source.size();
  const size_t source = n, sink = n + 1;
  Graph g(n + 2);
  for (size_t i = 0; i < n; ++i) {
    MS_CHECK(from_source[i] >= 0 && to_sink[i] >= 0);
    if (from_source[i] > 0) AddArcPair(g, source, i, from_source[i], 0);
    if (to_sink[i] > 0) AddArcPair(g, i, sink, to_sink[i], 0);
  }
  for (const CutEdge& e : edges) {
    MS_CHECK(e.a_to_b >= 0 && e.b_to_a >= 0 && e.a != e.b);
    AddArcPair(g, static_cast<size_t>(e.a), static_cast<size_t>(e.b), e.a_to_b, e.b_to_a);
  }
  boost::boykov_kolmogorov_max_flow(g, source, sink);
  // After the flow, the source's search tree is black; its residual reach is the source side.
  const auto color = boost::get(boost::vertex_color, g);
  const auto source_color = boost::get(color, source);
  std::vector<uint8_t> side(n);
  for (size_t i = 0; i < n; ++i) side[i] = boost::get(color, i) == source_color;
  return side;
}

}  // namespace ms::manifold_detail
