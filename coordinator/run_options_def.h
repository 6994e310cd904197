// The options of a coordinator run itself (iterations, outputs, progress, message size), one line
// each: MS_OPTION(type, name, default, flag, help, bound). Top-level flags (--max-iterations).
// Included by coordinator/coordinator.h only.

MS_OPTION(bool, resume, false, "resume",
          "continue the run in --output from its last checkpoint (run.h5); starts afresh if "
          "there is none",
          AnyValue())
MS_OPTION(int, max_iterations, 15, "max-iterations",
          "it_max: stop after this many sweep + insertion iterations", InRange(0, 1000))
MS_OPTION(bool, save_iteration_meshes, false, "save-iterations",
          "also write iteration_NN.ply after every iteration", AnyValue())
MS_OPTION(double, progress_interval_s, 5, "progress-interval",
          "seconds between progress lines while sweeping", Above(0))
#define MS_LINK_MESSAGE_SIZE_OPTION
#include "proto/link_options_def.h"
#undef MS_LINK_MESSAGE_SIZE_OPTION
// The capacity benchmark drives the coordinator with replaying workers on scenes without images.
MS_OPTION(bool, no_images, false, "no-images",
          "do not hash or serve image files: jobs carry none, so only workers with --kernel "
          "replay can take them (bench/scalability)",
          AnyValue())
