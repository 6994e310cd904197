// The options of the run report (`manisweep report`, and `reconstruct` at its end), one line each:
//   MS_OPTION(type, name, default, flag, help, bound)
// Included by report/report_options.h only (no include guard on purpose).

MS_OPTION(int, cameras, 3, "cameras",
          "views the meshes are rendered from, spread over the scene (0 = no pictures, and no "
          "error image)",
          InRange(0, 64))
MS_OPTION(int, picture_size, 360, "picture-size", "longest side of each picture in pixels",
          InRange(64, 4096))
MS_OPTION(bool, consistency, true, "consistency",
          "measure each mesh's photo-consistency (needs the images; =false skips it)", AnyValue())
MS_OPTION(std::string, ground_truth, "", "ground-truth",
          "ground-truth mesh for the accuracy table (empty: the gt.ply of a `synth` dataset "
          "found beside the run's input)",
          AnyValue())
MS_OPTION(double, sigma, 0, "sigma",
          "Sigma of the accuracy table in scene units (0: median ground-truth depth / 20)",
          AtLeast(0))
