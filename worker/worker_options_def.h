// The options of a worker process, one line each: MS_OPTION(type, name, default, flag, help,
// bound). Top-level flags (--liveness). Included by worker/worker_process.h only.

MS_OPTION(std::string, id, "", "id",
          "name in the coordinator's logs and statistics (default host:pid)", AnyValue())
#define MS_LINK_HEARTBEAT_OPTIONS
#define MS_LINK_MESSAGE_SIZE_OPTION
#include "proto/link_options_def.h"
#undef MS_LINK_HEARTBEAT_OPTIONS
#undef MS_LINK_MESSAGE_SIZE_OPTION
MS_OPTION(double, reconnect_initial_s, 0.5, "reconnect-initial",
          "first back-off before reconnecting (seconds); doubles each time", Above(0))
MS_OPTION(double, reconnect_max_s, 16, "reconnect-max",
          "longest back-off between reconnections (seconds; at least --reconnect-initial)",
          Above(0))
MS_OPTION(double, give_up_after_s, 300, "give-up-after",
          "exit with an error after this many seconds without a coordinator", Above(0))
// Debugging and tests: catch a worker in the middle of a job.
MS_OPTION(double, debug_delay_s, 0, "debug.delay-s", "testing: sleep this long before each sweep",
          InRange(0, 3600))
