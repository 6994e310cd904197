#include "app/distributed_options.h"

#include <cmath>

#include "base/error.h"
#include "worker/job_codec.h"

namespace ms::app {

void AddSweepOptions(CLI::App* cmd, SweepOptions* s) {
  cmd->add_option("--sweep.num-offsets", s->num_offsets, "N: sweep offsets k with -N/2 < k < N/2")
      ->capture_default_str();
  cmd->add_option("--sweep.alpha", s->alpha,
                  "sweep step in scene units; 0 = auto from the parallax (0.03 = the paper's 3 cm "
                  "in a metric scene)")
      ->capture_default_str();
  cmd->add_option("--sweep.alpha-parallax-px", s->alpha_parallax_px,
                  "auto alpha: pixels of parallax in the neighbours per step at the median depth")
      ->capture_default_str();
  cmd->add_option("--sweep.ncc-threshold", s->ncc_threshold, "t_NCC: keep tile winners above this")
      ->capture_default_str();
  cmd->add_option("--sweep.gaussian-sigma-px", s->gaussian_sigma_px,
                  "sigma of the NCC's Gaussian window (swept-resolution pixels)")
      ->capture_default_str();
  cmd->add_option("--sweep.tile-size-px", s->tile_size_px,
                  "tile size (swept-resolution pixels); one point per tile at most")
      ->capture_default_str();
  cmd->add_option("--sweep.min-texture-variance", s->min_texture_variance,
                  "textureless below this weighted variance (gray in [0, 1])")
      ->capture_default_str();
  cmd->add_option("--sweep.min-window-weight", s->min_window_weight,
                  "fraction of the Gaussian window that must be valid")
      ->capture_default_str();
  cmd->add_option("--sweep.occlusion-tolerance", s->occlusion_tolerance,
                  "relative depth tolerance of the neighbours' shadow maps")
      ->capture_default_str();
  cmd->add_option("--sweep.max-image-dimension", s->max_image_dimension,
                  "halve images until their longest side fits (0 = full size)")
      ->capture_default_str();
  cmd->add_option("--sweep.pyramid-level", s->pyramid_level,
                  "sweep at this pyramid level (-1 = from max-image-dimension, 0 = full size)")
      ->capture_default_str();
}

void AddRunOptions(CLI::App* cmd, CoordinatorOptions* run, SweepOptions* sweep,
                   double* max_message_mb) {
  cmd->add_flag("--resume", run->resume,
                "continue the run in --output from its last checkpoint (run.h5); starts afresh "
                "if there is none");
  cmd->add_option("--max-iterations", run->max_iterations,
                  "it_max: stop after this many sweep + insertion iterations")
      ->capture_default_str();
  cmd->add_flag("--save-iterations", run->save_iteration_meshes,
                "also write iteration_NN.ply after every iteration");
  cmd->add_option("--progress-interval", run->progress_interval_s,
                  "seconds between progress lines while sweeping")
      ->capture_default_str();

  ManifoldOptions& m = run->manifold;
  cmd->add_option("--manifold.w1", m.w1, "weight added to cells a viewing ray crosses")
      ->capture_default_str();
  cmd->add_option("--manifold.w2", m.w2, "weight added to the face neighbours of crossed cells")
      ->capture_default_str();
  cmd->add_option("--manifold.free-threshold", m.free_threshold,
                  "t_w: a cell is free space when its weight reaches this")
      ->capture_default_str();
  cmd->add_option("--manifold.steiner-margin", m.steiner_margin,
                  "Steiner box: bounding box enlarged by this fraction of its diagonal")
      ->capture_default_str();
  cmd->add_option("--manifold.steiner-grid", m.steiner_grid, "Steiner points per box edge (>= 2)")
      ->capture_default_str();
  cmd->add_option("--manifold.shrink-neighbourhood", m.shrink_neighbourhood,
                  "cells shrunk before an insertion: 0 = conflict region + face neighbours, 1 = "
                  "+ vertex neighbours")
      ->capture_default_str();
  cmd->add_flag("--manifold.grow-all-components", m.grow_all_components,
                "grow from every free-space component, not only the heaviest cell");

  NeighbourOptions& n = run->neighbours;
  cmd->add_option("--neighbours.count", n.count, "neighbour cameras per sweep job")
      ->capture_default_str();
  cmd->add_option("--neighbours.max-angle-deg", n.max_angle_deg,
                  "neighbours' viewing directions differ from the camera's by less than this")
      ->capture_default_str();
  cmd->add_option("--visible.margin-px", run->visible.margin_px,
                  "widen the frustum test of a job's visible mesh by this many pixels")
      ->capture_default_str();

  SchedulerOptions& s = run->scheduler;
  cmd->add_option("--lease", s.lease_s,
                  "seconds a worker may take for a job before it is given to another one")
      ->capture_default_str();
  cmd->add_option("--heartbeat-interval", s.heartbeat_interval_s,
                  "seconds between heartbeats (both ways; give workers the same value)")
      ->capture_default_str();
  cmd->add_option("--liveness", s.liveness,
                  "a worker silent for this many heartbeat intervals is presumed dead")
      ->capture_default_str();
  cmd->add_option("--max-attempts", s.max_attempts,
                  "hand-outs of one job without a result before the run fails")
      ->capture_default_str();
  cmd->add_option("--max-message-mb", *max_message_mb,
                  "largest protocol message in MiB (jobs carry the visible mesh); larger ones "
                  "are logged and dropped")
      ->capture_default_str();
  AddSweepOptions(cmd, sweep);
}

void FinishRunOptions(const SweepOptions& sweep, double max_message_mb, CoordinatorOptions* run) {
  sweep.Check();
  if (!(max_message_mb >= 0.0625 && max_message_mb <= 2048)) {
    throw InputError("--max-message-mb: must be in [1/16, 2048]");
  }
  run->limits.max_message_bytes = static_cast<uint64_t>(std::llround(max_message_mb * 1048576));
  run->limits.image_chunk_bytes =
      std::min<uint64_t>(run->limits.image_chunk_bytes, run->limits.max_message_bytes / 2);
  SweepOptionsToWire(sweep, &run->sweep);
}

}  // namespace ms::app
