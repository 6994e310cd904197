// Test helper: a child process of the manisweep binary with its output in a log file.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace ms::test {

class ChildProcess {
 public:
  // Starts `binary args...` with stdout and stderr appended to `log_path`.
  ChildProcess(const std::string& binary, const std::vector<std::string>& args,
               const std::string& log_path);
  ~ChildProcess();  // SIGKILLs and reaps it if still running
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  void Signal(int sig);
  // Waits up to timeout_s; returns true once exited (then exit_code() / term_signal() apply).
  bool Wait(double timeout_s);
  bool running();
  int exit_code() const { return exit_code_; }      // -1 unless it exited normally
  int term_signal() const { return term_signal_; }  // 0 unless killed by a signal
  std::string Log() const;
  // Waits until the log contains `text` (or the process exits / timeout). True if found.
  bool WaitForLog(const std::string& text, double timeout_s);

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1, term_signal_ = 0;
  std::string log_path_;
};

// A TCP port on 127.0.0.1 that was free a moment ago.
int FreePort();

}  // namespace ms::test
