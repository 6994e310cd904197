// The options of `manisweep extend` (adding images to a finished run), one line each:
// MS_OPTION(type, name, default, flag, help, bound). Included by coordinator/run_extension.h only.

// COLMAP's image_registrator and point_triangulator keep the registered images' poses; a bundle
// adjustment after them moves them a little. Past these bounds the new model is taken to be in
// another frame, or the old cameras to have moved so far that the run's surface no longer fits.
MS_OPTION(double, max_camera_shift, 0.01, "max-camera-shift",
          "most an old camera's centre may move in the new model, as a fraction of the run's "
          "median viewing distance",
          AtLeast(0))
MS_OPTION(double, max_camera_turn_deg, 1.0, "max-camera-turn-deg",
          "most an old camera may turn in the new model, in degrees", InRange(0, 180))
