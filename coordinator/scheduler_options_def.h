// The options of the job scheduler (leases, heartbeats, retries), one line each:
// MS_OPTION(type, name, default, flag, help, bound). Top-level flags (--lease). Included by
// coordinator/job_scheduler.h only.

// Longer than the slowest job you expect (a reference-kernel job at 1536 px takes a few seconds
// of one core).
MS_OPTION(double, lease_s, 600, "lease",
          "seconds a worker may take for a job before it is given to another one", Above(0))
#define MS_LINK_HEARTBEAT_OPTIONS
#include "proto/link_options_def.h"
#undef MS_LINK_HEARTBEAT_OPTIONS
MS_OPTION(int, max_attempts, 5, "max-attempts",
          "hand-outs of one job without a result before the run fails", InRange(1, 1000))
