// The options of a sweep job's visible mesh, one line each:
// MS_OPTION(type, name, default, flag, help, bound). Included by mesh/visible_mesh.h only.

// Lens distortion is ignored by the frustum test, so a margin keeps faces at the border.
MS_OPTION(double, margin_px, 0, "margin-px",
          "widen the frustum test of a job's visible mesh by this many pixels", AtLeast(0))
MS_OPTION(double, near, 0, "near",
          "faces whose vertices all lie closer than this (camera z, scene units) are left out; 0 "
          "keeps everything in front of the camera",
          AtLeast(0))
// For meshes of unknown orientation.
MS_OPTION(bool, keep_back_facing, false, "keep-back-facing",
          "keep faces that turn their back to the camera", AnyValue())
