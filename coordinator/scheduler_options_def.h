// The options of the job scheduler (leases, heartbeats, retries), one line each:
// MS_OPTION(type, name, default, flag, help, bound). Top-level flags (--lease). Included by
// coordinator/job_scheduler.h only.

// Longer than the slowest job you expect (a reference-kernel job at 1536 px takes a few seconds
// of one core).
MS_OPTION(double, lease_s, 600, "lease",
          "seconds a worker may take for a job before it is given to another one", Above(0))
MS_OPTION(double, heartbeat_interval_s, 1.0, "heartbeat-interval",
          "seconds between heartbeats (both ways; give workers the same value)",
          InRange(0.01, 3600))
MS_OPTION(int, liveness, 5, "liveness",
          "a worker silent for this many heartbeat intervals is presumed dead", InRange(2, 1000))
MS_OPTION(int, max_attempts, 5, "max-attempts",
          "hand-outs of one job without a result before the run fails", InRange(1, 1000))
