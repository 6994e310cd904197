#include "sweep/sweep_options.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "base/error.h"

namespace ms {

void SweepOptions::Check() const {
  const auto fail = [](const std::string& field, const std::string& what, double value) {
    throw InputError(fmt::format("sweep.{} {}, got {}", field, what, value));
  };
  if (num_offsets < 1 || num_offsets > 1000)
    fail("num_offsets", "must be in [1, 1000]", num_offsets);
  if (!(std::isfinite(alpha) && alpha >= 0))
    fail("alpha", "must be finite and >= 0 (0 = auto)", alpha);
  if (!(std::isfinite(alpha_parallax_px) && alpha_parallax_px > 0)) {
    fail("alpha_parallax_px", "must be finite and > 0", alpha_parallax_px);
  }
  if (!(ncc_threshold >= -1 && ncc_threshold <= 1))
    fail("ncc_threshold", "must be in [-1, 1]", ncc_threshold);
  if (!(gaussian_sigma_px >= 0.5 && gaussian_sigma_px <= 100)) {
    fail("gaussian_sigma_px", "must be in [0.5, 100]", gaussian_sigma_px);
  }
  if (tile_size_px < 1) fail("tile_size_px", "must be >= 1", tile_size_px);
  if (!(std::isfinite(min_texture_variance) && min_texture_variance >= 0)) {
    fail("min_texture_variance", "must be finite and >= 0", min_texture_variance);
  }
  if (!(min_window_weight > 0 && min_window_weight <= 1)) {
    fail("min_window_weight", "must be in (0, 1]", min_window_weight);
  }
  if (!(std::isfinite(occlusion_tolerance) && occlusion_tolerance >= 0)) {
    fail("occlusion_tolerance", "must be finite and >= 0", occlusion_tolerance);
  }
  if (max_image_dimension < 0)
    fail("max_image_dimension", "must be >= 0 (0 = full size)", max_image_dimension);
  if (pyramid_level < -1 || pyramid_level > 12) {
    fail("pyramid_level", "must be in [-1, 12] (-1 = auto)", pyramid_level);
  }
}

}  // namespace ms
