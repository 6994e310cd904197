// The options of the replay kernel (worker/replay_kernel.h), one line each: MS_OPTION(type,
// name, default, flag, help, bound). Flags --replay.NAME. Included by worker/replay_kernel.h only.

MS_OPTION(std::string, run, "", "run",
          "--kernel replay: the run.h5 of an earlier run of the same scene and options, whose "
          "points are handed back instead of sweeping",
          AnyValue())
// The delay stands in for a GPU's sweep of one job (docs/design/scalability.md gives its
// measured range).
MS_OPTION(double, delay_s, 0.3, "delay-s",
          "--kernel replay: seconds each job takes (the sweep time being simulated)",
          InRange(0, 3600))
