#include "worker/job_codec.h"

namespace ms {

void SweepOptionsToWire(const SweepOptions& o, wire::SweepOptions* out) {
  out->set_num_offsets(o.num_offsets);
  out->set_alpha(o.alpha);
  out->set_alpha_parallax_px(o.alpha_parallax_px);
  out->set_ncc_threshold(o.ncc_threshold);
  out->set_gaussian_sigma_px(o.gaussian_sigma_px);
  out->set_tile_size_px(o.tile_size_px);
  out->set_min_texture_variance(o.min_texture_variance);
  out->set_min_window_weight(o.min_window_weight);
  out->set_occlusion_tolerance(o.occlusion_tolerance);
  out->set_max_image_dimension(o.max_image_dimension);
  out->set_pyramid_level(o.pyramid_level);
}

SweepOptions SweepOptionsFromWire(const wire::SweepOptions& w) {
  SweepOptions o;
  o.num_offsets = w.num_offsets();
  o.alpha = w.alpha();
  o.alpha_parallax_px = w.alpha_parallax_px();
  o.ncc_threshold = w.ncc_threshold();
  o.gaussian_sigma_px = w.gaussian_sigma_px();
  o.tile_size_px = w.tile_size_px();
  o.min_texture_variance = w.min_texture_variance();
  o.min_window_weight = w.min_window_weight();
  o.occlusion_tolerance = w.occlusion_tolerance();
  o.max_image_dimension = w.max_image_dimension();
  o.pyramid_level = w.pyramid_level();
  return o;
}

void SweepResultToWire(const SweepResult& result, wire::Result* out) {
  out->clear_points();
  for (const SweepPoint& p : result.points) {
    wire::SweepPoint* w = out->add_points();
    w->set_x(p.position.x());
    w->set_y(p.position.y());
    w->set_z(p.position.z());
    w->set_ncc(p.ncc);
    w->set_pixel_x(p.pixel.x());
    w->set_pixel_y(p.pixel.y());
    w->set_offset(p.offset);
    w->set_face(p.face);
    for (int32_t c : p.cameras) w->add_cameras(c);
  }
  const SweepStats& s = result.stats;
  wire::KernelStats* k = out->mutable_stats();
  k->set_image_width(s.image_width);
  k->set_image_height(s.image_height);
  k->set_pyramid_level(s.pyramid_level);
  k->set_alpha(s.alpha);
  k->set_median_depth(s.median_depth);
  k->set_num_offsets(s.num_offsets);
  k->set_num_neighbours(s.num_neighbours);
  k->set_tiles_x(s.tiles_x);
  k->set_tiles_y(s.tiles_y);
  k->set_covered_pixels(s.covered_pixels);
  k->set_hypotheses(s.hypotheses);
  k->set_valid_hypotheses(s.valid_hypotheses);
  k->set_prepare_s(s.prepare_s);
  k->set_raster_s(s.raster_s);
  k->set_reproject_s(s.reproject_s);
  k->set_ncc_s(s.ncc_s);
  k->set_reduce_s(s.reduce_s);
  k->set_total_s(s.total_s);
}

}  // namespace ms
