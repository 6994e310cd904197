// The options of neighbour selection for the sweep (paper section 2.2), one line each:
// MS_OPTION(type, name, default, flag, help, bound). Included by scene/view_selection.h only.

// Strictly less than this: optical axes at this angle or more see too different a surface.
MS_OPTION(double, max_angle_deg, 60, "max-angle-deg",
          "neighbours' viewing directions differ from the camera's by less than this",
          InRangeOpenLow(0, 180))
MS_OPTION(int, count, 2, "count", "neighbour cameras per sweep job (fewer when fewer qualify)",
          AtLeast(0))
// Cameras at the same centre have no parallax, useless for stereo.
MS_OPTION(double, same_center_fraction, 1e-6, "same-center-fraction",
          "cameras closer than this fraction of the camera-centre bounding-box diagonal count as "
          "at the same centre and are skipped",
          InRangeOpenHigh(0, 1))
