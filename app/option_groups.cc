#include "app/option_groups.h"

#include <map>
#include <string>

namespace ms::app {

void RegisterManifoldOptions(CLI::App* cmd, ManifoldOptions* o) {
  cmd->add_option("--manifold.w1", o->w1, "w_1: weight a viewing ray adds to each cell it crosses")
      ->capture_default_str();
  cmd->add_option("--manifold.w2", o->w2,
                  "w_2: weight added to each face neighbour of a crossed cell")
      ->capture_default_str();
  cmd->add_option("--manifold.free-threshold", o->free_threshold,
                  "t_w: a cell is free space when its weight reaches this")
      ->capture_default_str();
  static const std::map<std::string, W2Rule> kW2Rules = {{"camera-side", W2Rule::kCameraSide},
                                                         {"all-faces", W2Rule::kAllFaces}};
  cmd->add_option("--manifold.w2-rule", o->w2_rule,
                  "which face neighbours of a crossed cell get w_2: camera-side (only between the "
                  "camera and the cell) or all-faces (the paper's wording)")
      ->transform(CLI::CheckedTransformer(kW2Rules, CLI::ignore_case))
      ->default_str("camera-side");
  cmd->add_option("--manifold.steiner-margin", o->steiner_margin,
                  "Steiner box: bounding box of points and cameras enlarged by this x its diagonal")
      ->capture_default_str();
  cmd->add_option("--manifold.steiner-grid", o->steiner_grid,
                  "Steiner points per edge of the box (2 = corners only)")
      ->capture_default_str();
  static const std::map<std::string, GradedSteiner> kGraded = {
      {"auto", GradedSteiner::kAuto}, {"on", GradedSteiner::kOn}, {"off", GradedSteiner::kOff}};
  cmd->add_option("--manifold.graded-steiner", o->steiner_graded,
                  "graded Steiner points in the empty space, cells of Steiner points only being "
                  "free: on, off (the paper's box grid only) or auto (on from "
                  "--manifold.graded-steiner-min-points points; docs/manifold.md)")
      ->transform(CLI::CheckedTransformer(kGraded, CLI::ignore_case))
      ->default_str("auto");
  cmd->add_option("--manifold.graded-steiner-min-points", o->graded_steiner_min_points,
                  "auto mode: input points from which graded Steiner points are used")
      ->capture_default_str();
  cmd->add_option("--manifold.steiner-clearance", o->steiner_clearance,
                  "graded Steiner points keep this x their size away from every point")
      ->capture_default_str();
  cmd->add_option("--manifold.steiner-min-spacing", o->steiner_min_spacing,
                  "smallest graded Steiner cell, in median point spacings")
      ->capture_default_str();
  cmd->add_option("--manifold.shrink-neighbourhood", o->shrink_neighbourhood,
                  "cells shrunk before an insertion: 0 = conflict region + face neighbours, "
                  "1 = + every cell sharing a vertex")
      ->capture_default_str();
  cmd->add_flag("--manifold.grow-all-components", o->grow_all_components,
                "grow every free-space component, not only the heaviest cell's");
  cmd->add_flag("--manifold.validate", o->validate_each_step,
                "check the whole state (labels, weights, manifold) after every step (slow)");
}

}  // namespace ms::app
