// Process plumbing for the distributed commands: stop signals (SIGINT/SIGTERM) as a flag that
// long loops poll, and child processes of this same binary (`manisweep reconstruct` starts its
// workers with them) that die with their parent.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace ms::app {

// SIGINT and SIGTERM set a flag instead of killing the process; a second SIGINT restores the
// default action (a second Ctrl-C kills at once). SIGPIPE is ignored.
void InstallStopSignals();
bool StopRequested();
int StopSignal();  // the signal that set the flag (0: none)

// Starts /proc/self/exe with `args` (argv[1..]). The child gets SIGTERM if this process dies
// (prctl PR_SET_PDEATHSIG), so no worker outlives its `reconstruct`. Throws InternalError if
// fork fails.
pid_t SpawnSelf(const std::vector<std::string>& args);

// Waits up to grace_s for the children to exit, then sends SIGTERM, waits another grace_s,
// then SIGKILL; reaps them all. Returns how many had to be signalled.
int StopChildren(const std::vector<pid_t>& pids, double grace_s);

}  // namespace ms::app
