// Child processes: fork and exec with everything the child needs prepared before the fork (only
// async-signal-safe calls between the two), output appended to a log file, and the child dying
// with its parent. `reconstruct` starts its workers with it, the colmap route colmap, the
// multi-process tests the binary under test.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace ms {

struct SubprocessOptions {
  std::string executable;         // path given to execve (no PATH search)
  std::vector<std::string> argv;  // argv[0] included
  std::vector<std::string> env;   // "NAME=value"; empty: this process's environment
  std::string output_path;        // stdout and stderr appended here (created); empty: inherited
  bool stdin_from_null = false;   // stdin from /dev/null; otherwise inherited
  bool die_with_parent = true;    // SIGTERM when the forking thread's process dies
  bool default_signals = true;    // SIGINT, SIGTERM and SIGPIPE back to their default actions
};

// Starts the child and returns its pid. Throws InternalError naming the output file or fork's
// error if it cannot. A failed exec ends the child with exit code 127.
pid_t StartSubprocess(const SubprocessOptions& options);

// "exit code 3", "killed by signal 9 (Killed)", from waitpid's status.
std::string DescribeExit(int status);

// Reaps `pid` if it has exited, without waiting: true and its waitpid status.
bool ReapIfExited(pid_t pid, int* status);

// Waits up to `timeout_s` for `pid` to exit (polling): true and its status if it did.
bool WaitForExit(pid_t pid, double timeout_s, int* status);

}  // namespace ms
