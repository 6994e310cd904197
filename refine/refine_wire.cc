#include "refine/refine_wire.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace ms {
namespace {

constexpr size_t kValues = 5;  // gradient x y z, parallax rate squared, weight

// Little-endian on the wire; this code assumes a little-endian host, as PackMesh does.
static_assert(sizeof(double) == 8 && sizeof(int32_t) == 4);

}  // namespace

void PairGradientToWire(const PairGradient& gradient, wire::PairGradient* out) {
  out->set_energy(gradient.energy);
  out->set_pixels(gradient.pixels);
  out->set_num_vertices(static_cast<uint32_t>(gradient.gradient.size()));
  std::vector<int32_t> ids;
  std::vector<double> values;
  for (size_t v = 0; v < gradient.gradient.size(); ++v) {
    const Eigen::Vector3d& g = gradient.gradient[v];
    // A vertex with only zeros adds nothing (x + 0 == x, and +0 + -0 == +0): it stays home.
    if (g.x() == 0 && g.y() == 0 && g.z() == 0 && gradient.parallax_rate2[v] == 0 &&
        gradient.weight[v] == 0) {
      continue;
    }
    ids.push_back(static_cast<int32_t>(v));
    values.insert(values.end(),
                  {g.x(), g.y(), g.z(), gradient.parallax_rate2[v], gradient.weight[v]});
  }
  out->set_vertices(reinterpret_cast<const char*>(ids.data()), ids.size() * sizeof(int32_t));
  out->set_values(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
}

PairGradient PairGradientFromWire(const wire::PairGradient& in, size_t num_vertices,
                                  std::string* problem) {
  problem->clear();
  PairGradient out;
  if (in.num_vertices() != num_vertices) {
    *problem = fmt::format("gradient for {} vertices, the job's mesh has {}", in.num_vertices(),
                           num_vertices);
    return out;
  }
  if (!std::isfinite(in.energy()) || in.energy() < 0 || in.pixels() < 0 ||
      in.energy() > static_cast<double>(in.pixels()) * 2 + 1e-9) {
    *problem = fmt::format("energy {} over {} pixels is impossible (1 - ZNCC is in [0, 2])",
                           in.energy(), in.pixels());
    return out;
  }
  const std::string& id_bytes = in.vertices();
  const std::string& value_bytes = in.values();
  const size_t listed = id_bytes.size() / sizeof(int32_t);
  if (id_bytes.size() % sizeof(int32_t) != 0 ||
      value_bytes.size() != listed * kValues * sizeof(double) || listed > num_vertices) {
    *problem = fmt::format("{} bytes of vertex ids and {} bytes of values do not fit together",
                           id_bytes.size(), value_bytes.size());
    return out;
  }
  out.Resize(num_vertices);
  out.energy = in.energy();
  out.pixels = in.pixels();
  int64_t previous = -1;
  for (size_t i = 0; i < listed; ++i) {
    int32_t v = 0;
    std::memcpy(&v, id_bytes.data() + i * sizeof(int32_t), sizeof(int32_t));
    double x[kValues];
    std::memcpy(x, value_bytes.data() + i * kValues * sizeof(double), sizeof(x));
    if (v <= previous || static_cast<size_t>(v) >= num_vertices) {
      *problem = fmt::format("vertex id {} (entry {}) is out of order or out of range", v, i);
      return PairGradient();
    }
    for (double value : x) {
      if (!std::isfinite(value)) {
        *problem = fmt::format("vertex {}: a value is not finite", v);
        return PairGradient();
      }
    }
    if (x[3] < 0 || x[4] < 0) {
      *problem = fmt::format("vertex {}: negative parallax rate or weight", v);
      return PairGradient();
    }
    previous = v;
    out.gradient[v] = Eigen::Vector3d(x[0], x[1], x[2]);
    out.parallax_rate2[v] = x[3];
    out.weight[v] = x[4];
  }
  return out;
}

}  // namespace ms
