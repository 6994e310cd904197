#include "worker/job_codec.h"

namespace ms {

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
  k->set_image_noise(s.image_noise);
  k->set_smoothing_px(s.smoothing_px);
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
